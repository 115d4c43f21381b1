"""The progressive schedule's rules: when a pass's image is denoised, how quick a preview is, how
small a draft is.

    if denoise_now(k, total, since, denoise_s):      # after pass k of total
        image, buf = job.preview(PREVIEW_K, PREVIEW_QUALITY)   # a quick preview
    w, h = draft_size(512, 512)                      # the draft's film: (139, 139)

The schedule (`progressive.schedule`) denoises the first pass that can be, the last, and any pass
where the passes since the last denoised image took at least as long as that denoising did and
that holds at least GROWTH times the camera samples of the denoised image on screen: the
first with a quick preview (`ExpectationJob.preview`: PREVIEW_K coverage points per pixel, OIDN
PREVIEW_QUALITY) where it serves (`quick_serves`), the others with the render's own denoiser.
Design: docs/design/progressive_schedule.md.
"""
from __future__ import annotations

#: the denoised previews between the passes: coverage points per pixel and OIDN's quality
#: (`ExpectationJob.preview`). Measured on the interior at 512 x 512 after its first pass (one
#: camera sample of 4 children): 'fast' 29.0-29.8 dB against the converged render, 'balanced'
#: 30.1-30.2 dB for about 0.1 s more, 'high' 30.3-30.6 dB for 0.5 s more; 16 points instead of 4
#: added 0.1 dB (docs/design/viewport.md)
PREVIEW_K, PREVIEW_QUALITY = 4, "balanced"
#: a denoised image is shown again only from at least GROWTH times the camera samples of the one on
#: screen: its expected distance to the final image then falls by about that factor, far more than
#: one image's realized distance strays from its expectation (cel on the Cornell box at 48 x 48,
#: denoised after every pass of one camera sample: 9.8e-4 from the final image after 4, 1.04e-3
#: after 5; after 1, 2, 4, 8 camera samples the distance fell every time)
GROWTH = 2
#: OIDN's quality for the draft, denoised as auto would whatever the render's Denoise says
DRAFT_QUALITY = "balanced"
#: the draft's largest film (pixels): a larger view is drafted at a reduced resolution
DRAFT_PIXELS = 160 * 120


def denoise_now(k: int, total: int, since: float, denoise_s: list[float]) -> bool:
    """Whether a progressive render denoises after pass `k` of `total`: the first pass that can
    be, the last, and any pass where the passes since the last denoised image took at least as
    long as that denoising did (so denoising takes at most about half the time;
    docs/design/viewport.md). Only ratios of times decide: a machine twice as fast (or a clock
    twice as slow) denoises after the same passes.

    Args:
        k, total: the pass (from 1) and the passes. since: seconds of passes since the last
            denoised image. denoise_s: the seconds of each denoising so far.

    Returns:
        True where this pass's image is denoised."""
    return k == total or not denoise_s or since >= denoise_s[-1]


def worth_showing(spp_done: int, shown_spp: int) -> bool:
    """Whether a denoised image of the passes so far may replace the one on screen: made from at
    least GROWTH times its camera samples (none shown yet: any).

    Args:
        spp_done: camera samples per pixel in the passes so far. shown_spp: those of the denoised
            image on screen (0: none).

    Returns:
        True where the new image is expected to be closer to the final one, beyond doubt.
    """
    return spp_done >= GROWTH * shown_spp


def quick_serves(spp_done: int) -> bool:
    """Whether a quick preview is at least as close to the final image as the raw image of the
    passes it is made from: while that raw image holds one camera sample per pixel. A quick
    preview's own error (g at PREVIEW_K stratified points per pixel, OIDN PREVIEW_QUALITY) stays as
    the passes add up; it is below one camera sample's (its pixel footprint seen at one point, its
    children's noise), not below that of several. Measured (mean squared distance to the final
    image, seed 3): after one camera sample of 4 children the quick preview was 3 to 11 times
    closer than the raw image on the Cornell box (cel, identity; 32 x 32), the dragon, the mixed
    scene (cel) and the Cornell box at 64 x 64 (sepia); with passes of 16 camera samples (Cornell
    box, 32 x 32, identity) it was 2.8e-2 at every pass, the raw image 8.5e-3 to 2.0e-3 and the
    render's own denoiser 2.5e-5 to 4.9e-6 (docs/design/progressive_schedule.md).

    Args:
        spp_done: camera samples per pixel in the passes so far.

    Returns:
        True for one camera sample per pixel.
    """
    return spp_done <= 1


def draft_size(width: int, height: int, limit: int = DRAFT_PIXELS) -> tuple[int, int]:
    """The draft's film: the view's size scaled down (same aspect) to `limit` pixels, each side
    rounded to whole pixels.

    Args:
        width, height: the view's size in pixels.
        limit: the draft's pixels (default `DRAFT_PIXELS`); a smaller view keeps its size.

    Returns:
        (width, height) of the draft, each at least 1.
    """
    scale = min(1.0, (limit / float(width * height)) ** 0.5)
    return max(1, round(width * scale)), max(1, round(height * scale))


__all__ = ["denoise_now", "worth_showing", "quick_serves", "draft_size", "GROWTH", "PREVIEW_K",
           "PREVIEW_QUALITY", "DRAFT_QUALITY", "DRAFT_PIXELS"]
