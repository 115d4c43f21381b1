"""Denoising at a budget (issue 21): `styletrace.render(..., denoise="expectation" | "image")`.

- `expectation` (`denoise.expectation`): denoise the per-pixel estimate of E[L] at the first
  stylized vertex, then apply g; step styles (cel, hatching) stay free of band flips, and the
  expectation buffer keeps the denoised expectation for millisecond restyles.
- `image` (`denoise.image`): render as usual and denoise the final image; the baseline.

Both use OIDN (`pyoidn`, the `styletrace[denoise]` extra) with albedo and normal guides through
mirrors and glass (`kernel.guides`), or Mitsuba's OptiX denoiser on CUDA (`denoise.oidn`,
untested). Which method a render gets is chosen when it is resolved
(`pipeline.denoising.choose_method`); `finishers` runs it as the pipeline's finisher (`plan`: the
run of a job, every front end's). Method, bias and the supported combinations: docs/denoise.md.
"""
from __future__ import annotations


class NotDenoised(UserWarning):
    """Issued by `styletrace.render` where the default (auto) could not denoise; the message says
    why, in one line."""


__all__ = ["NotDenoised"]
