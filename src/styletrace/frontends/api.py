"""The Python API: load a scene, build the `stylized` integrator, render in passes.

    import styletrace
    # H x W x 3 float32, linear
    img = styletrace.render("cornell-box", style="cel", spp=16, inner=8)
    img = styletrace.render("cornell-box", style="cel", samples=64)   # 4 camera samples x 16

`render` builds one `Job` of its keywords (`pipeline.job.python_job`), which
`denoise.finishers.plan` resolves once and runs. The building blocks live in `pipeline/` and
`scene/` and are re-exported here under their established names: loading (`scene.loading`), the
pass loop (`pipeline.passes`), the carried settings (`pipeline.carried`).
"""
from __future__ import annotations

from typing import Any, Callable

from styletrace.errors import SceneError, UsageError
from styletrace.images import PIXEL_FORMATS, save_safely, write_image
from styletrace.kernel.data_passes import Motion
from styletrace.kernel.integrator import StylizedIntegrator
from styletrace.pipeline.carried import carried_settings
from styletrace.pipeline.job import given_values
from styletrace.pipeline.passes import (
    LANE_BYTES,
    LANES_PER_PASS,
    TILE_SIDE,
    Progress,
    Tile,
    check_memory,
    expansion_seed,
    memory_available,
    memory_needed,
    pass_count,
    pass_seed,
    pass_size,
    passes,
    tiles,
)
from styletrace.scene.defaults import resolve_defaults as resolve_defaults
from styletrace.scene.loading import (
    SceneWarning,
    canonical_scene_normals,
    film_format,
    first_line,
    load_scene,
    scene_dict,
    scene_spp,
)
from styletrace.scene.plugins import init


def render(scene: Any = None, *, style: str | None = None, samples: int | None = None,
           spp: int | None = None, inner: Any = None, estimator: str | None = None, seed: int = 0,
           width: int | None = None, height: int | None = None,
           defines: dict[str, Any] | None = None, integrator: Any = None,
           sampler: str | None = None,
           pass_spp: int | None = None, denoise: str | None = None, denoise_quality: str = "high",
           coverage: int | str = "auto", denoise_uncertainty: float | None = None,
           denoise_footprint: str = "pixel", cluster: str | None = None,
           passes: Any = None, motion: Any = None, mist: Any = None,
           callback: Callable[[Progress], None] | None = None, **params: Any):
    """`styletrace.render`: a scene rendered with a style, denoised at defaults (docs/python.md).

    Every keyword is one of the user's settings, named here and in docs/python.md (this is why it
    takes more than 7 parameters); they become one `pipeline.job.Job` (`python_job`), which
    `denoise.finishers.plan` resolves once and runs.

    Args:
        scene: a built-in name, a Mitsuba XML file, a scene dict or an mi.Scene (None: the Cornell
            box).
        style: the style's name (None: the scene's own `stylized` integrator's, else identity,
            as the `stylized` plugin's default and Blender's render setting; the command line
            and the preview start from cel instead).
        samples: paths per pixel, the render's cost whatever the style (None: the scene's sample
            count), split into spp camera samples x inner children (`pipeline.budget`).
        spp: camera samples per pixel; inner: children per stylized vertex (a count, one per
            level, or 'n0:n_max'); None: chosen from samples.
        estimator: the estimator of g(E[L]) (None: direct). seed: the render's seed.
        width, height: the film's size (None: the scene's). defines: an XML file's `<default>`
            values. integrator: a prebuilt integrator, used as it is (not with style or params).
        sampler: a built-in scene's sampler, owen_sobol or independent (None: owen_sobol, the
            built-in scenes'); a scene file or dict names its own.
        pass_spp: camera samples per pixel per pass (None: by memory).
        denoise: auto, expectation, image or off (None: $STYLETRACE_DENOISE, else auto).
        denoise_quality, coverage, denoise_uncertainty, denoise_footprint: the denoiser's options
            (`pipeline.denoising.Denoising`, docs/denoise.md).
        cluster: "local" or a Ray address: the passes as Ray tasks (the merged image denoised
            here by the image denoiser); None: here.
        passes: data passes beside the image: 'depth,normal,vector' or a list of the names of
            `kernel.data_passes.DATA_PASSES` (None: none; docs/passes.md).
        motion: the neighbouring frames of the vector pass (`kernel.data_passes.Motion`: the
            camera's to_world one frame before and after, moving shapes); None: a still (0).
        mist: the mist pass's (start, depth, falloff) or 'START,DEPTH,FALLOFF' (None: a new
            Blender World's 5, 25, 'quadratic'; `kernel.mist`).
        callback: called with each pass's `Progress`.
        **params: the style's parameters and the integrator's other properties, by name.

    Returns:
        The image, float32 H x W x C, linear; or (image, aovs) with aovs=True or data passes
        asked for (aovs: {name: array}, the error AOVs and the data passes by name).

    Raises:
        StyletraceError: a bad value or a refused combination (one line), before rendering.

    Warns:
        NotDenoised: auto could not denoise (the message says why).
    """
    from styletrace.denoise import NotDenoised
    from styletrace.denoise.finishers import plan
    from styletrace.pipeline.denoising import Denoising
    from styletrace.pipeline.execute import executor_for
    from styletrace.pipeline.job import python_job
    denoising = Denoising(denoise, denoise_quality, coverage, denoise_uncertainty,
                          denoise_footprint)
    job = python_job(scene, style=style, samples=samples, spp=spp, inner=inner,
                     estimator=estimator, seed=seed, width=width, height=height, defines=defines,
                     integrator=integrator, sampler=sampler, pass_spp=pass_spp,
                     denoising=denoising, passes=passes, motion=motion, mist=mist,
                     **params)
    runner = plan(job, executor_for(cluster))
    if runner.resolved.note:
        import warnings
        warnings.warn(runner.resolved.note, NotDenoised, stacklevel=2)
    return runner.result(callback)


def make_integrator(style: str | None = None, inner: Any = None, estimator: str | None = None,
                    **params: Any) -> StylizedIntegrator:
    """A `stylized` integrator; what is not given takes its default (`config.settings`).

    Args:
        style, estimator: their names. inner: `inner_samples` (None: the style's; per level (8, 4)).
        **params: integrator properties (stylize, stylize_depth, max_depth, rr_depth, ...) and the
            style's parameters, under their names.

    Returns:
        The StylizedIntegrator.

    Raises:
        StyletraceError: an unknown name or a bad value (one line).
    """
    return make_integrator_from(given_values(style, inner, estimator, **params))


def make_integrator_from(values: dict[str, Any]) -> StylizedIntegrator:
    """A `stylized` integrator from its property values (the backend chosen first, `init`).

    Args:
        values: {name: value} of the style, its parameters, inner_samples and other properties.

    Returns:
        The StylizedIntegrator.

    Raises:
        StyletraceError: an unknown name or a bad value (one line).
    """
    init()
    return StylizedIntegrator.from_values(values)


__all__ = ["render", "load_scene", "carried_settings", "film_format", "scene_spp", "SceneWarning",
           "make_integrator", "make_integrator_from", "passes", "resolve_defaults", "pass_count",
           "SceneError", "Progress", "StylizedIntegrator", "write_image", "save_safely", "Motion",
           # re-exported under their established names (the module docstring)
           "UsageError", "PIXEL_FORMATS", "LANE_BYTES", "LANES_PER_PASS", "TILE_SIDE", "Tile",
           "check_memory", "expansion_seed", "memory_available", "memory_needed", "pass_seed",
           "pass_size", "tiles", "canonical_scene_normals", "first_line", "scene_dict"]
