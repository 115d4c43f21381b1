"""Reference-free measures of a rendered image, as a user judges a default (docs/look.md).

    noise_psnr(a, b)        PSNR (dB) of two renders differing only in seed, in display space
    firefly_share(img)      share of pixels brighter than 5x the median of their 5 x 5
                            neighbourhood (a median of at least 0.01)
    speck_share(img)        share of pixels darker than 1/5 of that median (a median of at
                            least 0.05): a firefly's mirror, which a defect that stays put
                            between seeds leaves and noise_psnr cannot see
    clipped_share(img), crushed_share(img)
                            pixels with every channel >= 0.99 / <= 0.01 in display space
    tone_correlation(img, ref, period)
                            rank correlation of local luminance with a converged render
    windows(x, size)        every element's size x size neighbourhood, edges repeated

Images are H x W x 3 float arrays of linear radiance; display space is sRGB of the values clamped to
[0, 1]. numpy only.
"""
from __future__ import annotations

import numpy as np

#: a pixel is a firefly above this multiple of its neighbourhood's median luminance
FIREFLY_RATIO = 5.0
FIREFLY_WINDOW = 5
#: the least median a firefly is measured against (1% of display white): a dark pixel among black
#: ones is noise nobody sees, not a firefly
FIREFLY_FLOOR = 0.01


def srgb(img: np.ndarray) -> np.ndarray:
    """The sRGB encoding of linear values clamped to [0, 1] (NaN as 0).

    Args:
        img: array-like of linear values, any shape.

    Returns:
        float64 array of the same shape, in [0, 1].
    """
    x = np.clip(np.nan_to_num(np.asarray(img, dtype=np.float64), nan=0.0), 0.0, 1.0)
    return np.where(x <= 0.0031308, 12.92 * x, 1.055 * np.power(x, 1 / 2.4) - 0.055)


def luminance(img: np.ndarray) -> np.ndarray:
    """The Rec. 709 luminance of linear RGB.

    Args:
        img: H x W x 3 array-like (or any shape with RGB on the last axis).

    Returns:
        float64 array without the last axis (H x W).
    """
    img = np.asarray(img, dtype=np.float64)
    return img[..., 0] * 0.2126 + img[..., 1] * 0.7152 + img[..., 2] * 0.0722


def noise_psnr(a: np.ndarray, b: np.ndarray) -> float:
    """The PSNR of one render's noise, from two renders differing only in seed.

    Args:
        a, b: H x W x 3 linear images of one scene and settings, different seeds.

    Returns:
        PSNR in dB, peak 1, with the per-render variance mean((a - b)^2) / 2 in display space;
        inf for identical images.
    """
    var = float(np.mean((srgb(a) - srgb(b)) ** 2)) / 2.0
    return float("inf") if var == 0.0 else float(10.0 * np.log10(1.0 / var))


def windows(x: np.ndarray, size: int) -> np.ndarray:
    """The size x size neighbourhood of every element of a 2-D array, edges repeated.

    Args:
        x: H x W array.
        size: the neighbourhood's side (odd).

    Returns:
        An H x W x size x size view of x (no copy).
    """
    r = size // 2
    padded = np.pad(x, r, mode="edge")
    return np.lib.stride_tricks.sliding_window_view(padded, (size, size))


def _local_median(img: np.ndarray, size: int) -> tuple[np.ndarray, np.ndarray]:
    """(luminance, its median over each size x size neighbourhood) of a linear image, NaN and
    negatives as 0."""
    lum = luminance(np.maximum(np.nan_to_num(np.asarray(img, dtype=np.float64)), 0.0))
    return lum, np.median(windows(lum, size), axis=(-2, -1))


def firefly_share(img: np.ndarray, ratio: float = FIREFLY_RATIO,
                  size: int = FIREFLY_WINDOW) -> float:
    """The share of pixels that are fireflies, on the linear image (NaN and negatives as 0).

    Args:
        img: H x W x 3 linear image.
        ratio: a pixel is a firefly when its luminance exceeds `ratio` times the median of its
            neighbourhood, that median taken as at least FIREFLY_FLOOR.
        size: the neighbourhood's side in pixels (odd; edges repeated).

    Returns:
        The fraction of pixels, in [0, 1].
    """
    lum, median = _local_median(img, size)
    return float(np.mean(lum > ratio * np.maximum(median, FIREFLY_FLOOR)))


#: a pixel is a dark speck below the median of its neighbourhood over this
SPECK_RATIO = FIREFLY_RATIO
#: the least median a speck is measured against (5% of display white): a black pixel among dim
#: ones is seen as little as a dim one among black
SPECK_FLOOR = 0.05


def speck_share(img: np.ndarray, ratio: float = SPECK_RATIO,
                size: int = FIREFLY_WINDOW) -> float:
    """The share of pixels that are dark specks in a bright neighbourhood, on the linear image
    (NaN and negatives as 0).

    Args:
        img: H x W x 3 linear image.
        ratio: a pixel is a speck when its luminance is below the median of its neighbourhood
            over `ratio`, where that median is at least SPECK_FLOOR.
        size: the neighbourhood's side in pixels (odd; edges repeated).

    Returns:
        The fraction of pixels, in [0, 1].
    """
    lum, median = _local_median(img, size)
    return float(np.mean((median >= SPECK_FLOOR) & (lum < median / ratio)))


def clipped_share(img: np.ndarray) -> float:
    """The share of pixels with every channel at or above 0.99 in display space.

    Args:
        img: H x W x 3 linear image.

    Returns:
        The fraction of pixels, in [0, 1].
    """
    return float(np.mean(np.all(srgb(img) >= 0.99, axis=-1)))


def crushed_share(img: np.ndarray) -> float:
    """The share of pixels with every channel at or below 0.01 in display space.

    Args:
        img: H x W x 3 linear image.

    Returns:
        The fraction of pixels, in [0, 1].
    """
    return float(np.mean(np.all(srgb(img) <= 0.01, axis=-1)))


def _box_blur(x: np.ndarray, size: int) -> np.ndarray:
    if size <= 1:
        return x
    return np.mean(windows(x, size | 1), axis=(-2, -1))


def _ranks(x: np.ndarray) -> np.ndarray:
    order = np.argsort(x, kind="stable")
    ranks = np.empty(len(x), dtype=np.float64)
    ranks[order] = np.arange(len(x), dtype=np.float64)
    # ties share their mean rank
    values, inverse, counts = np.unique(x, return_inverse=True, return_counts=True)
    sums = np.bincount(inverse, weights=ranks)
    return (sums / counts)[inverse]


def tone_correlation(img: np.ndarray, reference: np.ndarray, period: int = 8,
                     mask: np.ndarray | None = None) -> float:
    """Spearman's rank correlation between the blurred display luminance of two images.

    Args:
        img: H x W x 3 linear image.
        reference: a converged render of the same shape.
        period: the side in pixels of the box blur (made odd; <= 1: none): the pattern's period,
            so that a screen of lines or dots reads as its tone.
        mask: H x W booleans, the pixels compared (after the blur), or None: all.

    Returns:
        The correlation in [-1, 1]; 0 where either image is flat (or the mask is empty).
    """
    a = _box_blur(luminance(srgb(img)), period)
    b = _box_blur(luminance(srgb(reference)), period)
    a, b = (a.ravel(), b.ravel()) if mask is None else (a[mask], b[mask])
    ra, rb = _ranks(a), _ranks(b)
    ra -= ra.mean()
    rb -= rb.mean()
    denom = np.sqrt((ra * ra).sum() * (rb * rb).sum())
    return float((ra * rb).sum() / denom) if denom > 0 else 0.0


__all__ = ["srgb", "luminance", "noise_psnr", "firefly_share", "clipped_share", "crushed_share",
           "tone_correlation", "FIREFLY_RATIO", "FIREFLY_WINDOW", "FIREFLY_FLOOR"]
