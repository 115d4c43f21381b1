"""The description of one render: what every front end builds and hands to `resolve`, then
to `execute`.

    job = Job(scene="scene.xml", defines={"depth": "3"}, width=64, height=48,
              given={"style": "cel", "inner_samples": 8}, spp=16, seed=0)

A `Job` holds what the caller said and nothing derived: the scene source (a built-in name, an XML
path, a scene dict or an mi.Scene), the defines of the file's `<default>` parameters, the film size,
the integrator values given (they refine the scene's own `stylized` integrator, or the scene's
carried settings over `default_style`), or a prebuilt integrator used as it is, and the sampling:
spp (None: the scene sampler's count), seed and the pass split (`pass_spp`, `lanes_per_pass`; None:
the device's, `sizing`). It is frozen: resolving it twice gives the same scene, integrator
and passes.
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

    def __post_init__(self):
        if self.integrator is not None and self.given:
            raise UsageError(
                f"bad arguments: integrator= is used as it is, so {', '.join(sorted(self.given))} "
                f"cannot refine it; pass either a prebuilt integrator or style= and parameters"
            )

    def with_(self, **changes: Any) -> "Job":
        """This job with some fields replaced (a frame of a turntable, another seed)."""
        return replace(self, **changes)


def given_values(style: str | None = None, inner: Any = None, estimator: str | None = None,
                 **params: Any) -> dict[str, Any]:
    """The integrator values of the Python API's keywords, leaving out what was not given (None)."""
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
    **params: Any,
) -> "Job":
    """The Job of a Python API call (`styletrace.render`, `render_buffer`, `render(denoise=...)`):
    its keywords as the pipeline's description, integrator values given only where not None."""
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
    )


def check_counts(*named: tuple[str, Any]) -> None:
    """A one-line UsageError for the first (name, value) whose value is given (not None) and below
    1: the sizes and sample counts of the command line's render and preview."""
    for name, value in named:
        if value is not None and value < 1:
            raise UsageError(f"bad value {value} for {name}: expected an integer >= 1")


__all__ = ["Job", "given_values", "python_job", "check_counts", "PYTHON_STYLE"]
