"""Statistical tests for comparing renders and estimators, with tolerances derived from the data.

Everything here is elementary (numpy + math) so that the truth of a test does not rest on the code
under test.
"""
from __future__ import annotations

import math

import numpy as np


def t_sf(t: float, dof: int) -> float:
    """P(T > t) for Student's t with `dof` degrees of freedom (numerical integration of the
    density)."""
    if t < 0:
        return 1.0 - t_sf(-t, dof)
    logc = math.lgamma((dof + 1) / 2) - math.lgamma(dof / 2) - 0.5 * math.log(dof * math.pi)
    # substitute x = t + s/(1-s) to integrate the tail over s in [0, 1)
    s = np.linspace(0.0, 1.0, 200001)[:-1]
    x = t + s / (1.0 - s)
    dens = np.exp(logc - (dof + 1) / 2 * np.log1p(x * x / dof)) / (1.0 - s) ** 2
    return float(np.trapz(dens, s)) if hasattr(np, "trapz") else float(np.trapezoid(dens, s))


def t_quantile(p_upper: float, dof: int) -> float:
    """t such that P(T > t) = p_upper (bisection on t_sf)."""
    lo, hi = 0.0, 1e3
    for _ in range(100):
        mid = 0.5 * (lo + hi)
        if t_sf(mid, dof) > p_upper:
            lo = mid
        else:
            hi = mid
    return 0.5 * (lo + hi)


def blocks(a: np.ndarray, size: int) -> np.ndarray:
    """Average (K, H, W, C) images over size x size pixel blocks (H, W cropped to multiples of
    size)."""
    k, h, w, c = a.shape
    h, w = h - h % size, w - w % size
    return a[:, :h, :w].reshape(k, h // size, size, w // size, size, c).mean(axis=(2, 4))


def pixel_t_test(a: np.ndarray, b: np.ndarray, alpha: float = 1e-3, block: int = 1):
    """Per-pixel two-sample test of equal means from K independent renders of each side.

    a, b: arrays (K, H, W, C). The per-pixel differences of independent renders D_k = a_k - b_k have
    mean zero under the null hypothesis; t = mean(D)/(sd(D)/sqrt(K)) follows Student's t with K-1
    degrees of freedom (each render averages many samples, so D_k is close to normal). The threshold
    is Bonferroni-corrected for the number of pixel channels tested at family-wise level `alpha`.
    `block` > 1 tests block averages instead of pixels: estimators with rare large samples (a light
    found only by BSDF sampling) need more samples per tested value before the normal approximation
    holds. Returns (max |t|, threshold, fraction of channels over the threshold).

    The normal approximation is this test's precondition, and an unbiased estimator breaks it when a
    pixel's mean is carried by rare large samples that most renders do not contain: those renders
    agree with one another (the sample sd is small) and all fall short of the mean, so |t| is large
    with no bias at all. first_n_hits at stylize_depth 2 under a small bright area light is such an
    estimator (the level above the last finds surface lights by BSDF sampling only, docs/guide.md):
    at 4 spp x inner 4, max |t| 28 over 8.3 where a third of the pixels hold no light sample in all
    16 renders, the image means agreeing (tests/test_stats_helpers.py has the same failure from an
    exactly unbiased toy estimator). Give each render enough samples that every tested value holds
    several of the rare ones (more spp, or `block`), and check that |t| falls as they grow: a bias
    makes it grow as the square root of the spp.
    """
    if block > 1:
        a, b = blocks(a, block), blocks(b, block)
    d = (a - b).reshape(a.shape[0], -1).astype(np.float64)
    k = d.shape[0]
    sd = d.std(axis=0, ddof=1)
    mean = d.mean(axis=0)
    ok = sd > 0
    t = np.zeros(d.shape[1])
    t[ok] = mean[ok] / (sd[ok] / math.sqrt(k))
    # deterministic on both sides (the sky seen directly): equal up to float32 rounding, or no noise
    # explains it
    scale = np.abs(a).reshape(k, -1).mean(axis=0) + np.abs(b).reshape(k, -1).mean(axis=0)
    t[~ok & (np.abs(mean) > 1e-6 * scale)] = np.inf
    m = int(ok.sum())
    thr = t_quantile(alpha / (2 * max(m, 1)), k - 1)
    return float(np.abs(t).max()), thr, float((np.abs(t) > thr).mean())


def mean_threshold(k: int, alpha: float = 1e-4, channels: int = 3) -> float:
    """Two-sided threshold for `mean_z` at family-wise level alpha over the channels: the
    statistic uses variances estimated from K renders per side, so Student's t with 2K - 2
    degrees of freedom applies."""
    return t_quantile(alpha / (2 * channels), 2 * k - 2)


def mean_z(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Per-channel z-score of the image-mean difference, from K independent renders of each side.

    The image mean of each render is one sample; the K renders of each side are independent, so the
    standard error of the difference of their averages follows from the two sample variances.
    """
    ma = a.reshape(a.shape[0], -1, a.shape[-1]).mean(axis=1).astype(np.float64)
    mb = b.reshape(b.shape[0], -1, b.shape[-1]).mean(axis=1).astype(np.float64)
    se = np.sqrt(ma.var(axis=0, ddof=1) / len(ma) + mb.var(axis=0, ddof=1) / len(mb))
    return (ma.mean(axis=0) - mb.mean(axis=0)) / se
