"""The Python API: load a scene, build the `stylized` integrator, render in passes.

    import styletrace
    # H x W x 3 float32, linear
    img = styletrace.render("cornell-box", style="cel", spp=16, inner=8)
    img = styletrace.render("cornell-box", style="cel", samples=64)   # 4 camera samples x 16

`render` is the render pipeline's (`pipeline.execute.render_pipeline`): a `Job` resolved once and
executed. The building blocks live in `pipeline/` and `scene/` and are re-exported here under
their established names: loading (`scene.loading`), the pass loop (`pipeline.passes`), the carried
settings (`pipeline.carried`).
"""
from __future__ import annotations

from typing import Any

from styletrace.errors import SceneError, UsageError
from styletrace.images import PIXEL_FORMATS, save_safely, write_image
from styletrace.kernel.integrator import StylizedIntegrator
from styletrace.pipeline.carried import carried_settings
from styletrace.pipeline.execute import render_pipeline as pipeline_render
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


def render(
    *args: Any,
    denoise: str | None = None,
    cluster: str | None = None,
    callback: Any = None,
    denoise_quality: str = "high",
    coverage: int | str = "auto",
    denoise_uncertainty: float | None = None,
    denoise_footprint: str = "pixel",
    **kw: Any,
):
    """`styletrace.render`: the render pipeline's; a denoiser finishes it unless denoise is off.

    Args:
        *args, **kw, callback, cluster: as `pipeline.execute.render_pipeline`'s (scene, style,
            samples, spp, inner, ...).
        denoise: auto, expectation, image or off (None: $STYLETRACE_DENOISE, else auto).
        denoise_quality, coverage, denoise_uncertainty, denoise_footprint: as
            `denoise.render_denoised`'s.

    Returns:
        The image, float32 H x W x C, or (image, aovs) with aovs=True.

    Raises:
        UsageError: an unknown denoise method; a refusal of the run (one line).
    """
    from styletrace.denoise import check_method, default_method
    method = check_method(denoise if denoise is not None else default_method())
    if method == "off":
        return pipeline_render(*args, cluster=cluster, callback=callback, **kw)
    from styletrace.denoise import render_denoised as denoised
    from styletrace.pipeline.job import python_job
    return denoised(python_job(*args, **kw), method, callback, cluster, denoise_quality, coverage,
                    denoise_uncertainty, denoise_footprint)


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
           "SceneError", "Progress", "StylizedIntegrator", "write_image", "save_safely",
           # re-exported under their established names (the module docstring)
           "UsageError", "PIXEL_FORMATS", "LANE_BYTES", "LANES_PER_PASS", "TILE_SIDE", "Tile",
           "check_memory", "expansion_seed", "memory_available", "memory_needed", "pass_seed",
           "pass_size", "tiles", "canonical_scene_normals", "first_line", "scene_dict"]
