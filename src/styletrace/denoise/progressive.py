"""When a progressive render shows a denoised image: Blender's viewport and the browser preview.

    if denoise_now(k, total, since, denoise_s):      # after pass k of total
        image, buf = job.preview(PREVIEW_K, PREVIEW_QUALITY)   # or, after the last, job.finish()

Both render one camera sample per pass and denoise the first pass, the last, and any pass where
the passes since the last denoised image took at least as long as that denoising did; before the
last pass with a quick preview (`ExpectationJob.preview`: PREVIEW_K coverage points per pixel,
OIDN PREVIEW_QUALITY), after it with the render's own finisher. Design: docs/design/viewport.md,
"The schedule (issue 36)", and docs/design/preview_session.md.
"""
from __future__ import annotations

#: the denoised previews between the passes: coverage points per pixel and OIDN's quality
#: (`ExpectationJob.preview`). Measured on the interior at 512 x 512 after its first pass (one
#: camera sample of 4 children): 'fast' 29.0-29.8 dB against the converged render, 'balanced'
#: 30.1-30.2 dB for about 0.1 s more, 'high' 30.3-30.6 dB for 0.5 s more; 16 points instead of 4
#: added 0.1 dB (docs/design/viewport.md)
PREVIEW_K, PREVIEW_QUALITY = 4, "balanced"


def denoise_now(k: int, total: int, since: float, denoise_s: list[float]) -> bool:
    """Whether a progressive render denoises after pass `k` of `total`: the first pass that can
    be, the last, and any pass where the passes since the last denoised image took at least as
    long as that denoising did (so denoising takes at most about half the time;
    docs/design/viewport.md).

    Args:
        k, total: the pass (from 1) and the passes. since: seconds of passes since the last
            denoised image. denoise_s: the seconds of each denoising so far.

    Returns:
        True where this pass's image is denoised and shown."""
    return k == total or not denoise_s or since >= denoise_s[-1]


__all__ = ["denoise_now", "PREVIEW_K", "PREVIEW_QUALITY"]
