"""Restyles at slider speed: one point per pixel, θ as the kernel's inputs.

    img = quick_restyle(buf, style="cel", levels=(0.1, 0.3, 0.6))   # H x W x 3, a few ms

While a value is dragged, every new value must be on screen at once. A restyle of a whole
denoised buffer evaluates g at every coverage point (16 per pixel at 512 x 512). `quick_restyle`
restyles the buffer's one-point-per-pixel view (`restyle.per_pixel`, made once per buffer), with
θ passed to the kernel as inputs as every restyle does (`restyle.opaque_style`), so the kernel
compiled for the first value serves the later ones. Its image is each pixel's first point, that
point's value in a restyle of the whole buffer; the full look is `restyle.restyle`'s, shown when
the drag rests. `quick_restyle_pixels` adds the 8-bit sRGB RGBA pixels a page draws, encoded on the
device in the same trip (encoded on the host right after a restyle, the same pixels took 3 to 5
times as long on two cores, Dr.Jit's threads still busy). Design: docs/design/slider_restyles.md.
"""
from __future__ import annotations

from typing import Any

import numpy as np

from styletrace.gate import dr, mi
from styletrace.lookdev.restyle import as_buffer, per_pixel, restyle, restyled


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


def srgb8_rgba(image: mi.Float, width: int, height: int) -> np.ndarray:
    """A flat H*W*3 linear RGB image encoded on the device as a canvas takes it: 8-bit sRGB, RGBA
    (alpha 255), rows from the top; clamped to [0, 1] first (NaN as 0), as `images.srgb8`.

    Args:
        image: mi.Float, row-major RGB (`restyle.restyled`). width, height: its size.

    Returns:
        H x W x 4 uint8.
    """
    i = dr.arange(mi.UInt32, width * height) * 3
    packed = mi.UInt32(0xFF000000)
    for c in range(3):
        x = dr.gather(mi.Float, image, i + c)
        x = dr.select(dr.isnan(x), 0.0, dr.clip(x, 0.0, 1.0))
        enc = dr.select(x <= 0.0031308, 12.92 * x, 1.055 * dr.power(x, 1 / 2.4) - 0.055)
        packed |= mi.UInt32(dr.round(enc * 255.0)) << (8 * c)
    # little-endian: each pixel's bytes are R, G, B, A
    return np.asarray(packed).astype("<u4").view(np.uint8).reshape(height, width, 4)


def quick_restyle_pixels(buffer: Any, style: str | None = None, estimator: str | None = None,
                         inner: Any = None, **params: Any) -> tuple[np.ndarray, np.ndarray]:
    """`quick_restyle`, and its image encoded on the device for a page (`srgb8_rgba`).

    Args, Raises: as `quick_restyle`'s.

    Returns:
        (H x W x 3 float32 linear, H x W x 4 uint8 sRGB RGBA).
    """
    view = per_pixel(as_buffer(buffer))
    img = restyled(view, style, estimator, inner, **params)
    w, h = view.width, view.height
    return (np.asarray(img, dtype=np.float32).reshape(h, w, 3), srgb8_rgba(img, w, h))


__all__ = ["quick_restyle", "quick_restyle_pixels", "srgb8_rgba"]
