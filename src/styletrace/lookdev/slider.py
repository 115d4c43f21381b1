"""Restyles at slider speed: one point per pixel, θ as the kernel's inputs.

    img = quick_restyle(buf, style="cel", levels=(0.1, 0.3, 0.6))   # H x W x 3, a few ms

While a value is dragged, every new value must be on screen at once. A restyle of a whole
denoised buffer evaluates g at every coverage point (16 per pixel at 512 x 512). `quick_restyle`
restyles the buffer's one-point-per-pixel view (`restyle.per_pixel`, made once per buffer), with
θ passed to the kernel as inputs as every restyle does (`restyle.opaque_style`), so the kernel
compiled for the first value serves the later ones. Its image is each pixel's first point, that
point's value in a restyle of the whole buffer; the full look is `restyle.restyle`'s, shown when
the drag rests. Design: docs/design/slider_restyles.md.
"""
from __future__ import annotations

from typing import Any

import numpy as np

from styletrace.lookdev.restyle import as_buffer, per_pixel, restyle


def quick_restyle(buffer: Any, style: str | None = None, estimator: str | None = None,
                  inner: Any = None, **params: Any) -> np.ndarray:
    """The buffer's one-point-per-pixel view restyled (module doc).

    Args:
        buffer: a "mean" Buffer (denoised or not) or its .npz path; style, estimator, inner,
            params: as `restyle.restyle`'s.

    Returns:
        H x W x 3 float32, linear: each pixel the value of its first sample (`per_pixel`).

    Raises:
        UsageError: a change the buffer cannot replay, a sequence buffer; StyleError,
            SettingsError: bad values (one line each).
    """
    return restyle(per_pixel(as_buffer(buffer)), style, estimator, inner, **params)


__all__ = ["quick_restyle"]
