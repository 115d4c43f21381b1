"""Denoising at a budget (issue 21): `styletrace.render(..., denoise="expectation" | "image")`.

- `expectation` (`denoise.expectation`): denoise the per-pixel estimate of E[L] at the first
  stylized vertex, then apply g. Step styles (cel, hatching) stay free of band flips; works through
  the expectation buffer, which keeps the denoised expectation for millisecond restyles.
- `image` (`denoise.image`): render as usual and denoise the final image; the baseline.

Both use OIDN (`pyoidn`, the `styletrace[denoise]` extra) with albedo and normal guides (through
mirrors and glass) (`denoise.guides`), or Mitsuba's OptiX denoiser on CUDA (`denoise.oidn`,
untested). Method, bias and the supported combinations: docs/denoise.md.

`render` takes the pipeline's job (`styletrace.render` builds it from its keywords) and `denoise`
(auto, expectation, image or off; the default of every front end is auto, or $STYLETRACE_DENOISE:
`default_method`), `denoise_quality` ("high"), and for `expectation` `coverage` ("auto": 64 points
per pixel where the style meets D, `denoise.coverage`) and `denoise_uncertainty` (0.3: the style
averaged over D's residual error, `expectation.spread`; 0 for g of D). Returns the image, or (image,
aovs) with `aovs=True`.
"""
from __future__ import annotations

from typing import Any

from styletrace.denoise.default import ENV, METHODS, check_method, default_method


class NotDenoised(UserWarning):
    """Issued by `render` where the default (auto) could not denoise; the message says why, in
    one line."""


def render_denoised(
    job: Any,
    denoise: str = "auto",
    callback: Any = None,
    cluster: str | None = None,
    denoise_quality: str = "high",
    coverage: int | str = "auto",
    denoise_uncertainty: float | None = None,
):
    """`styletrace.render(..., denoise=...)`: the pipeline's `job` (`pipeline.job.Job`) resolved,
    planned (`finishers.plan`: auto picks expectation where it applies, else renders as the pipeline
    does and warns `NotDenoised`), and run by the pipeline's runner with the denoiser as its
    finisher (docs/denoise.md). `cluster`: the passes on Ray, which no denoiser takes (auto renders
    them undenoised)."""
    check_method(denoise)
    from styletrace.denoise.finishers import plan_finisher
    from styletrace.pipeline.execute import executor_for
    from styletrace.pipeline.resolve import resolve

    runner, note = plan_finisher(
        resolve(job),
        denoise,
        executor_for(cluster),
        quality=denoise_quality,
        coverage=coverage,
        uncertainty=denoise_uncertainty,
    )
    if note:
        import warnings
        warnings.warn(note, NotDenoised, stacklevel=3)
    return runner.result(callback)


__all__ = ["render", "METHODS", "ENV", "NotDenoised", "check_method", "default_method"]
