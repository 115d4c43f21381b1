"""The Cryptomatte standard's ranking filter: per pixel, the coverage of each id over the pixel's
camera samples (a box filter: each sample weighs 1 / spp), the ids ranked by coverage, the first
`levels` written as (id, coverage) pairs, two to an RGBA layer.

    ranked = ranks(bits, levels=6)   # bits: pixels x spp uint32 ids (float32 bits), 0: nothing
    ranked[:, 0].view(np.uint32)     # the most covering id of each pixel; ranked[:, 1] its share

Numpy only: the samples' ids are copied out of the kernel once, and a pixel holds at most spp ids.
Docs: docs/passes.md (Cryptomatte).
"""
from __future__ import annotations

import numpy as np

from styletrace.errors import UsageError

#: ids ranked per pixel: the standard's suggested default and Cycles' (3 RGBA layers)
LEVELS = 6


def ranks(bits: np.ndarray, levels: int = LEVELS) -> np.ndarray:
    """The ranked ids and coverages of some pixels.

    Args:
        bits: pixels x spp uint32, each camera sample's id (`cryptomatte.id_bits`), 0 where the
            sample met nothing (it covers no id: a pixel's coverages then sum to less than 1).
        levels: ids kept per pixel (>= 1).

    Returns:
        pixels x (2 * levels) float32: id 0, its coverage, id 1, its coverage, ...; the ids
        sorted by coverage, the larger first (equal coverages: the smaller id's bits first);
        (0, 0) in the slots of a pixel with fewer ids.

    Raises:
        UsageError: levels below 1.
    """
    if int(levels) < 1:
        raise UsageError(f"bad value {levels} for the Cryptomatte levels: expected >= 1")
    bits = np.asarray(bits, dtype=np.uint32)
    pixels, spp = bits.shape
    ordered = np.sort(bits, axis=1)
    # a run of equal ids in a sorted row is one id's samples
    starts = np.ones((pixels, spp), bool)
    starts[:, 1:] = ordered[:, 1:] != ordered[:, :-1]
    slot = np.cumsum(starts, axis=1) - 1 + np.arange(pixels)[:, None] * spp
    counts = np.bincount(slot.ravel(), minlength=pixels * spp).reshape(pixels, spp)
    ids = np.zeros(pixels * spp, np.uint32)
    ids[slot[starts]] = ordered[starts]
    ids = ids.reshape(pixels, spp)
    counts[ids == 0] = 0  # the samples that met nothing
    order = np.argsort(-counts, axis=1, kind="stable")[:, :levels]
    top_ids = np.take_along_axis(ids, order, axis=1)
    top = np.take_along_axis(counts, order, axis=1)
    out = np.zeros((pixels, 2 * int(levels)), np.float32)
    kept = top.shape[1]  # fewer than `levels` where spp is smaller
    out[:, 0:2 * kept:2] = np.where(top > 0, top_ids, 0).view(np.float32)
    out[:, 1:2 * kept:2] = top / np.float32(spp)
    return out


__all__ = ["LEVELS", "ranks"]
