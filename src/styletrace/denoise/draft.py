"""The preview's draft pass, denoised: the 1-spp, n = 1 draft buffer gets a denoised expectation, so
the restyles shown while the first full pass renders are clean instead of speckled
(docs/preview.md).

    denoised = draft(buf, scene, seed)     # True when the buffer now holds D, False without pyoidn

Parameters: `quality` OIDN's filter quality, default "balanced" for the draft (interaction first:
about half of "high"'s time, BENCHMARKS.md). Without the `denoise` extra the draft stays as it was
(the preview must open on any install); the full passes are never denoised (they converge to the
render the page's command line makes). The draft styles D at its own camera samples (`--coverage
0`): the page restyles this very buffer, in place.
"""
from __future__ import annotations

from styletrace.lookdev.buffer import Buffer

QUALITY = "balanced"


def available() -> bool:
    """Whether pyoidn (the `denoise` extra) is installed."""
    try:
        import pyoidn  # noqa: F401
    except ImportError:
        return False
    return True


def draft(buf: Buffer, scene, seed: int, quality: str = QUALITY) -> bool:
    """Denoise the draft buffer's expectation in place (`expectation.attach`, k = 0).

    Args:
        buf: the draft buffer (first_hit, a buffer of means). scene: its scene.
        seed: the render's seed. quality: OIDN's quality (QUALITY: "balanced").

    Returns:
        True when the buffer now holds D; False without pyoidn or for another kind of buffer.
    """
    if not available() or buf.stylize != "first_hit" or buf.stores != "mean":
        return False
    from styletrace.denoise.expectation import attach
    attach(buf, scene, buf.spp, seed, quality)
    return True


__all__ = ["draft", "available", "QUALITY"]
