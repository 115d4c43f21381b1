"""The description of one render: what every front end builds and hands to `resolve`, then
to `execute`.

    job = Job(scene="scene.xml", defines={"depth": "3"}, width=64, height=48,
              given={"style": "cel", "inner_samples": 8}, spp=16, seed=0)
    job = Job(scene="scene.xml", samples=64)   # 64 paths per pixel, split by `resolve`

A `Job` holds what the caller said and nothing derived (its fields: `Job`). It is frozen:
resolving it twice gives the same scene, integrator and passes.
Design: docs/design/render_pipeline.md.
"""
from __future__ import annotations

from dataclasses import dataclass, field, replace
from typing import Any, Mapping

from styletrace.errors import UsageError
from styletrace.pipeline.denoising import OFF, Denoising
from styletrace.pipeline.terms import PYTHON, Terms

#: the style of a scene without a `stylized` integrator when the caller names none (Python:
#: physically based)
PYTHON_STYLE = "identity"


@dataclass(frozen=True)
class Job:
    """What a caller asked for, nothing derived; frozen: resolving it twice gives the same render.

    Args:
        scene: a built-in name, an XML path, a scene dict or an mi.Scene (None: the default scene).
        defines: the XML file's `<default>` parameters. width, height: the film (None: the scene's).
        sampler: a built-in scene's sampler (`config.choices.SAMPLERS`; None: the scene's own;
            a file or dict names its own: `scene.loading.load_scene`).
        given: integrator values, laid over the scene's own `stylized` integrator, else over its
            carried settings with `default_style` (PYTHON_STYLE by default).
        integrator: a prebuilt integrator, used as it is (with `given` too: a UsageError).
        spp: camera samples per pixel (None: chosen from samples, `pipeline.budget`); seed: the
            render's seed.
        pass_spp, lanes_per_pass: the pass split, camera samples per pixel per pass and lanes per
            launch (None: the device's, `sizing`). pass_growth: each round of passes twice the
            one before, from pass_spp (`passes.PassSplit.rounds`).
        samples: paths per pixel, the render's cost whatever the style (None: the scene sampler's
            count), split into spp x children by `pipeline.budget`.
        denoising: the denoising asked for (`pipeline.denoising.Denoising`; default off: a plain
            pipeline run); `resolve` chooses the method before it splits the samples.
        max_camera_samples: the most camera samples an expectation buffer of this render holds
            (None: `pipeline.budget.MAX_CAMERA_SAMPLES`).
        terms: how the caller names the settings, for errors (`pipeline.terms`).
        draft: a glimpse of this render: one camera sample of the children its split gives
            (`resolve` asks the budget for that smaller request, `budget.draft_request`).
        data_passes: the data passes asked for beside the image (`kernel.data_passes`: depth,
            normal, vector; a comma-separated string or names), checked by `resolve`.
        motion: the neighbouring frames of the Vector pass (`kernel.data_passes.Motion`), or None
            (a still: its vector is 0).
        mist: the Mist pass's settings (`kernel.mist.parse_mist`'s values: (start, depth,
            falloff), 'START,DEPTH,FALLOFF'; None: Blender's defaults), checked by `resolve`.
    """
    scene: Any = None
    defines: Mapping[str, Any] = field(default_factory=dict)
    width: int | None = None
    height: int | None = None
    sampler: str | None = None
    given: Mapping[str, Any] = field(default_factory=dict)
    default_style: str = PYTHON_STYLE
    integrator: Any = None
    spp: int | None = None
    seed: int = 0
    pass_spp: int | None = None
    lanes_per_pass: int | None = None
    pass_growth: bool = False
    samples: int | None = None
    denoising: Denoising = OFF
    max_camera_samples: int | None = None
    terms: Terms = PYTHON
    draft: bool = False
    data_passes: Any = ()
    motion: Any = None
    mist: Any = None

    def __post_init__(self):
        if self.integrator is not None and self.given:
            raise UsageError(
                f"bad arguments: integrator= is used as it is, so {', '.join(sorted(self.given))} "
                f"cannot refine it; pass either a prebuilt integrator or style= and parameters"
            )

    def load(self, width: int | None = None, height: int | None = None):
        """The job's scene, loaded (`scene.loading.load_scene`).

        Args:
            width, height: a film size in place of the job's (a draft's); None: the job's.

        Returns:
            The mi.Scene.

        Raises:
            SceneError: a scene that cannot be found, loaded, resized or rendered.
        """
        from styletrace.scene.loading import load_scene
        return load_scene(self.scene, width or self.width, height or self.height,
                          dict(self.defines) or None, self.sampler)

    @property
    def cap(self) -> int:
        """The most camera samples an expectation buffer of this render holds."""
        from styletrace.pipeline.budget import MAX_CAMERA_SAMPLES
        return MAX_CAMERA_SAMPLES if self.max_camera_samples is None else self.max_camera_samples

    def with_(self, **changes: Any) -> "Job":
        """This job with some fields replaced (a frame of a turntable, another seed, a draft).

        Args:
            **changes: field names and their new values.

        Returns:
            A new Job.

        Raises:
            UsageError: the new job sets both `integrator` and `given`.
        """
        return replace(self, **changes)


def given_values(style: str | None = None, inner: Any = None, estimator: str | None = None,
                 **params: Any) -> dict[str, Any]:
    """The integrator values of the Python API's keywords, leaving out what was not given (None).

    Args:
        style: the style's name. inner: `inner_samples` (a count, one per level, or 'n0:n_max').
        estimator: the estimator's name. **params: other integrator properties, style parameters.

    Returns:
        {property name: value} of the arguments that are not None.
    """
    given = {"style": style, "inner_samples": inner, "estimator": estimator, **params}
    return {k: v for k, v in given.items() if v is not None}


def python_job(scene: Any = None, *, style: str | None = None, samples: int | None = None,
               spp: int | None = None, inner: Any = None, estimator: str | None = None,
               seed: int = 0, width: int | None = None, height: int | None = None,
               integrator: Any = None, defines: Mapping[str, Any] | None = None,
               sampler: str | None = None, pass_spp: int | None = None, denoising: Denoising = OFF,
               max_camera_samples: int | None = None, passes: Any = None, motion: Any = None,
               mist: Any = None, **params: Any) -> Job:
    """The Job of the Python API's keywords: the one place that reads them (`styletrace.render`,
    `render_buffer` and the other calls build on it).

    Takes more than 7 parameters: each is one of `styletrace.render`'s documented keywords
    (docs/python.md), named rather than passed down as a bag.

    Args:
        scene: a built-in name, an XML path, a scene dict or an mi.Scene.
        samples, spp, seed, width, height, integrator, defines, sampler, pass_spp, denoising,
            max_camera_samples, motion, mist: as `Job`'s fields. passes: `Job.data_passes`.
        style, inner, estimator, **params: the integrator values given (`given_values`: None
            leaves a value out).

    Returns:
        The Job, in the Python API's terms; its `given` holds only the values that are not None.

    Raises:
        UsageError: a prebuilt `integrator` together with values to refine it.
    """
    return Job(scene=scene, defines=dict(defines or {}), width=width, height=height,
               sampler=sampler, given=given_values(style, inner, estimator, **params),
               integrator=integrator, spp=spp, seed=seed, pass_spp=pass_spp, samples=samples,
               denoising=denoising, max_camera_samples=max_camera_samples, terms=PYTHON,
               data_passes=() if passes is None else passes, motion=motion, mist=mist)


def check_counts(*named: tuple[str, Any]) -> None:
    """Refuse the first (name, value) whose value is given (not None) and below 1.

    Args:
        *named: (flag, value) pairs: the sizes and sample counts of the command line's render and
            preview.

    Raises:
        UsageError: one line naming the flag and its value.
    """
    for name, value in named:
        if value is not None and value < 1:
            raise UsageError(f"bad value {value} for {name}: expected an integer >= 1")


__all__ = ["Job", "given_values", "python_job", "check_counts", "PYTHON_STYLE"]
