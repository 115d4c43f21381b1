"""Spacing and angle of a periodic stroke pattern in part of an image, from the peak of its 2D
spectrum."""
from __future__ import annotations

import numpy as np


def peak(ink: np.ndarray, region: np.ndarray, pad: int = 1024) -> tuple[float, float, float]:
    """(spacing in pixels, angle in degrees in [0, 180), peak magnitude / mean magnitude) of the
    strongest periodic component of `ink` (float image) inside the boolean `region`. The region's
    mean is removed and it is zero-padded to `pad` (a frequency bin of 1/pad cycles per pixel),
    then the peak is refined by a parabola through its neighbours on each axis. Angle: the
    direction of the frequency vector, i.e. the lines' normal, measured counter-clockwise from
    the image's x axis with y pointing up."""
    a = np.where(region, ink - ink[region].mean(), 0.0)
    F = np.abs(np.fft.fft2(a, s=(pad, pad)))
    F[0, 0] = 0.0
    fy = np.fft.fftfreq(pad)
    # only one half-plane: the spectrum of a real image is symmetric
    F[:, pad // 2:] = 0.0
    F[pad // 2:, 0] = 0.0
    iy, ix = np.unravel_index(np.argmax(F), F.shape)

    def refine(line, i):
        l, c, r = line[(i - 1) % pad], line[i], line[(i + 1) % pad]
        den = l - 2 * c + r
        return 0.0 if den == 0 else 0.5 * (l - r) / den

    ux = fy[ix] + refine(F[iy, :], ix) / pad
    uy = fy[iy] + refine(F[:, ix], iy) / pad
    f = np.hypot(ux, uy)
    # rows run down the image: flip y so the angle is counter-clockwise with y up
    angle = np.degrees(np.arctan2(-uy, ux)) % 180.0
    contrast = F[iy, ix] / F[F > 0].mean()
    return 1.0 / f, angle, contrast


def amplitude(ink_img, region, spacing):
    """The pattern's amplitude: the largest |Fourier coefficient| per region pixel on the circle of
    frequency 1/spacing (the peak), from a zero-padded spectrum."""
    pad = 1024
    a = np.where(region, ink_img - ink_img[region].mean(), 0.0)
    F = np.abs(np.fft.fft2(a, s=(pad, pad)))
    f = np.hypot(*np.meshgrid(np.fft.fftfreq(pad), np.fft.fftfreq(pad)))
    ring = np.abs(f - 1.0 / spacing) < 2.0 / pad
    return float(F[ring].max() / region.sum())


def angle_diff(a: float, b: float) -> float:
    """Difference of two line directions (mod 180 degrees), in [0, 90]."""
    d = abs(a - b) % 180.0
    return min(d, 180.0 - d)
