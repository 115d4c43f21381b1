"""Denoising at a budget (issue 21): `styletrace.render(..., denoise="expectation" | "image")`.

- `expectation` (`denoise.expectation`): denoise the per-pixel estimate of E[L] at the first
  stylized vertex, then apply g; step styles (cel, hatching) stay free of band flips, and the
  expectation buffer keeps the denoised expectation for millisecond restyles.
- `image` (`denoise.image`): render as usual and denoise the final image; the baseline.

Both use OIDN (`pyoidn`, the `styletrace[denoise]` extra) with albedo and normal guides through
mirrors and glass (`denoise.guides`), or Mitsuba's OptiX denoiser on CUDA (`denoise.oidn`,
untested). `default` chooses the method at defaults, `finishers` runs it as the pipeline's
finisher. Method, bias and the supported combinations: docs/denoise.md.
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
    denoise_footprint: str = "pixel",
):
    """`styletrace.render(..., denoise=...)`: the job run with a denoiser as its finisher.

    Args:
        job: the pipeline's `pipeline.job.Job`. callback: called with each pass's `Progress`.
        denoise: auto (expectation where it applies, else `finishers.plan_finisher`'s choice, with a
            `NotDenoised` warning where it does not denoise), expectation, image or off.
        cluster: the passes on Ray, which no denoiser takes (auto renders them undenoised).
        denoise_quality: OIDN's "high", "balanced" or "fast". coverage: `coverage.check_k`'s k.
        denoise_uncertainty: `expectation.spread`'s factor (None: 0.3; 0: g of D itself).
        denoise_footprint: the image denoiser's, "pixel" or "film" (`denoise.image`).

    Returns:
        The image, or (image, aovs) with aovs=True.
    """
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
        footprint=denoise_footprint,
    )
    if note:
        import warnings
        warnings.warn(note, NotDenoised, stacklevel=3)
    return runner.result(callback)


__all__ = ["render_denoised", "METHODS", "ENV", "NotDenoised", "check_method", "default_method"]
