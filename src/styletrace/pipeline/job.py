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

#: the style of a scene without a `stylized` integrator when the caller names none (Python:
#: physically based)
PYTHON_STYLE = "identity"


@dataclass(frozen=True)
class Job:
    """What a caller asked for, nothing derived; frozen: resolving it twice gives the same render.

    Args:
        scene: a built-in name, an XML path, a scene dict or an mi.Scene (None: the default scene).
        defines: the XML file's `<default>` parameters. width, height: the film (None: the scene's).
        given: integrator values, laid over the scene's own `stylized` integrator, else over its
            carried settings with `default_style` (PYTHON_STYLE by default).
        integrator: a prebuilt integrator, used as it is (with `given` too: a UsageError).
        spp: camera samples per pixel (None: chosen from samples, `pipeline.budget`); seed: the
            render's seed.
        pass_spp, lanes_per_pass: the pass split (None: the device's, `sizing`).
        samples: paths per pixel, the render's cost whatever the style (None: the scene sampler's
            count), split into spp x children by `pipeline.budget`.
    """
    scene: Any = None
    defines: Mapping[str, Any] = field(default_factory=dict)
    width: int | None = None
    height: int | None = None
    given: Mapping[str, Any] = field(default_factory=dict)
    default_style: str = PYTHON_STYLE
    integrator: Any = None
    spp: int | None = None
    seed: int = 0
    pass_spp: int | None = None
    lanes_per_pass: int | None = None
    samples: int | None = None

    def __post_init__(self):
        if self.integrator is not None and self.given:
            raise UsageError(
                f"bad arguments: integrator= is used as it is, so {', '.join(sorted(self.given))} "
                f"cannot refine it; pass either a prebuilt integrator or style= and parameters"
            )

    def with_(self, **changes: Any) -> "Job":
        """This job with some fields replaced (a frame of a turntable, another seed).

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


def python_job(
    scene: Any = None,
    style: str | None = None,
    spp: int | None = None,
    inner: Any = None,
    estimator: str | None = None,
    seed: int = 0,
    width: int | None = None,
    height: int | None = None,
    integrator: Any = None,
    defines: dict[str, Any] | None = None,
    pass_spp: int | None = None,
    samples: int | None = None,
    **params: Any,
) -> "Job":
    """The Job of a Python API call (`styletrace.render`, `render_buffer`, `render(denoise=...)`).

    Args:
        scene, spp, seed, width, height, integrator, defines, pass_spp, samples: as `Job`'s
            fields.
        style, inner, estimator, **params: the integrator values given (`given_values`: None
            leaves a value out).

    Returns:
        The Job; its `given` holds only the values that are not None.

    Raises:
        UsageError: a prebuilt `integrator` together with values to refine it.
    """
    return Job(
        scene=scene,
        defines=dict(defines or {}),
        width=width,
        height=height,
        given=given_values(style, inner, estimator, **params),
        integrator=integrator,
        spp=spp,
        seed=seed,
        pass_spp=pass_spp,
        samples=samples,
    )


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
