"""Tone from the scene's brightness distribution: where step styles put their levels.

Reference: Praun, Hoppe, Webb, Finkelstein, "Real-Time Hatching" (2001); CIE 1976 L*.

The tone of a brightness u is
    F(u) = (1 - PERCEPTUAL) CDF(u) + PERCEPTUAL L*(u / white) / 100,   white = the 98% quantile.
`tone_knots` returns the brightness at F = 0, 1/K, ..., 1 (piecewise linear in between); `tone_of`
evaluates F from knots inside a kernel; `band_levels` places cel's levels. Rationale:
docs/design/tone_curve.md.
"""
from __future__ import annotations

from typing import Callable, Sequence

import numpy as np

#: knots of the tone curve (K + 1 brightnesses)
TONE_KNOTS = 8
#: the weight of lightness against the equal-area CDF in F
PERCEPTUAL = 0.1
#: the quantiles that bound the tone curve: darker is full tone, lighter is none
LOW_Q, HIGH_Q = 0.02, 0.98
#: cel: the least lightness (CIE L*) between neighbouring levels, and the range the levels stay in
MIN_STEP_LSTAR = 18.0
LSTAR_RANGE = (12.0, 92.0)
#: the display value the scene's median brightness is exposed to (as the tone styles' `exposure`)
MIDDLE_GREY = 0.18


def lightness(y) -> np.ndarray:
    """CIE 1976 L* of relative luminance y (1 = white), in [0, 100] for y in [0, 1].

    Args:
        y: relative luminances (numbers or a numpy array; below 0 taken as 0).

    Returns:
        L*, numpy float64.
    """
    y = np.maximum(np.asarray(y, dtype=np.float64), 0.0)
    return np.where(y > (6 / 29) ** 3, 116.0 * np.cbrt(y) - 16.0, y * (29 / 3) ** 3)


def luminance_of(lstar) -> np.ndarray:
    """The relative luminance of lightness L* (the inverse of `lightness`).

    Args:
        lstar: lightness values (numbers or a numpy array).

    Returns:
        y, numpy float64.
    """
    lstar = np.asarray(lstar, dtype=np.float64)
    return np.where(lstar > 8.0, ((lstar + 16.0) / 116.0) ** 3, lstar / (29 / 3) ** 3)


def tone_knots(quantile: Callable[[Sequence[float]], list[float]],
               knots: int = TONE_KNOTS) -> list[float]:
    """The brightnesses u_0 <= ... <= u_K where F (module doc) is 0, 1/K, ..., 1.

    Args:
        quantile: quantile(qs) -> the scene's brightness quantiles
            (`scene.defaults.Facts.brightness`).
        knots: K.

    Returns:
        K + 1 non-decreasing floats (equal where the brightness is; `base.increasing` spreads them).
    """
    qs = np.linspace(LOW_Q, HIGH_Q, 65)
    u = np.maximum.accumulate(np.asarray(quantile(list(qs)), dtype=np.float64))
    white = max(u[-1], 1e-12)
    cdf = (qs - qs[0]) / (qs[-1] - qs[0])
    lstar = lightness(u / white)
    span = lstar[-1] - lstar[0]
    light = (lstar - lstar[0]) / span if span > 1e-9 else cdf
    f = (1.0 - PERCEPTUAL) * cdf + PERCEPTUAL * light
    out = np.interp(np.linspace(0.0, 1.0, knots + 1), f, u)
    return [float(x) for x in out]


def band_levels(quantile: Callable[[Sequence[float]], list[float]], bands: int) -> list[float]:
    """cel's target brightness per band, in display units: each band's median brightness (quantile
    (j + 1/2) / bands) under the exposure that maps the scene's median to middle grey (0.18), spread
    to at least MIN_STEP_LSTAR of lightness between neighbours and kept in LSTAR_RANGE.

    Args:
        quantile: quantile(qs) -> brightness quantiles, as in `tone_knots`.
        bands: the number of levels.

    Returns:
        `bands` increasing floats in (0, 1).
    """
    qs = [0.5] + [(j + 0.5) / bands for j in range(bands)]
    u = np.asarray(quantile(qs), dtype=np.float64)
    exposure = MIDDLE_GREY / max(u[0], 1e-12)
    lstar = np.clip(lightness(np.maximum.accumulate(u[1:]) * exposure), 0.0, 100.0)
    lo, hi = LSTAR_RANGE
    steps = np.maximum(np.diff(lstar), MIN_STEP_LSTAR)
    least = MIN_STEP_LSTAR * len(steps)
    # too wide: shrink what exceeds the least step, or make all steps equal
    if steps.sum() > hi - lo:
        steps = (
            np.full_like(steps, (hi - lo) / max(len(steps), 1))
            if least >= hi - lo
            else MIN_STEP_LSTAR
            + (steps - MIN_STEP_LSTAR) * (hi - lo - least) / (steps.sum() - least)
        )
    spread = np.concatenate([[0.0], np.cumsum(steps)])
    spread += lstar.mean() - spread.mean()
    spread += max(lo - spread[0], 0.0) - max(spread[-1] - hi, 0.0)
    return [float(x) for x in luminance_of(spread)]


def tone_of(u, knots: Sequence[float]):
    """F(u) from `tone_knots`' knots on Dr.Jit arrays: 0 at and below the first knot, 1 at and
    above the last, linear in between.

    Args:
        u: brightness (mi.Float per lane; drjit.clip refuses numpy arrays).
        knots: u_0 <= ... <= u_K (K >= 1).

    Returns:
        F(u) in [0, 1], of u's kind.
    """
    import drjit as dr
    k = len(knots) - 1
    out = 0.0 * u
    for a, b in zip(knots, knots[1:]):
        width = b - a
        if width > 0.0:
            out = out + dr.clip((u - a) * (1.0 / width), 0.0, 1.0)
        else:
            out = out + dr.select(u >= a, 1.0, 0.0)
    return out * (1.0 / k)


def tone_inverse(f, knots: Sequence[float]):
    """The brightness u where F(u) = f (the inverse of `tone_of` on the knots' range).

    Args:
        f: tone values, a float or a Dr.Jit array (clamped to [0, 1] per segment).
        knots: u_0 <= ... <= u_K (K >= 1).

    Returns:
        u in [u_0, u_K], of f's kind.
    """
    k = len(knots) - 1
    out = knots[0] + 0.0 * f
    for j, (a, b) in enumerate(zip(knots, knots[1:])):
        part = f * k - j
        part = min(max(part, 0.0), 1.0) if isinstance(part, float) else _clip01(part)
        out = out + part * (b - a)
    return out


def _clip01(x):
    import drjit as dr
    return dr.clip(x, 0.0, 1.0)


__all__ = ["TONE_KNOTS", "tone_inverse", "lightness", "luminance_of", "tone_knots", "band_levels",
           "tone_of"]
