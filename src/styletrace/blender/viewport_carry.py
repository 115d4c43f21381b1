"""The viewport's image carried to a moved view: what a camera move shows before the new session's
first pass (docs/design/viewport.md, "A camera move").

    mine, view = surfaces(draft_scene, before=old.surfaces)  # this view's points, at draft size
    image, kept = carried(old_image, old.surfaces, view)     # the old image, seen from here

Each session traces, once, the surfaces of its view at the draft's size (one camera ray per pixel:
`kernel.data_passes`' Depth, Normal and Vector, the vector towards the view before). The image on
screen is then carried to the new view with Render Animation's reprojection
(`denoise.temporal.reprojected`): each new pixel takes the bilinear mean of the old image around
where its surface point was in the old view, over the old pixels that saw the same surface (depth
and normal within `temporal`'s tolerances). A pixel whose surface the old view did not see (it was
hidden, or outside the old image) or that sees the world (no surface: its normal is none) is filled
from the carried pixels nearest to it (`filled`).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from styletrace.denoise.temporal import Accumulated, FrameView, reprojected
from styletrace.kernel.data_passes import Motion, View, render_data_passes

#: the surfaces' seed: one jitter for every view (the reprojection's truth is the geometry)
SEED = 0


@dataclass(frozen=True)
class Surfaces:
    """What each pixel of a view sees, at the draft's size.

    Args:
        view: the view's camera (`kernel.data_passes.View`: its pixel map, its size).
        depth: H x W, the distance along the view axis to the point the pixel sees.
        normal: H x W x 3, that point's world-space shading normal (0 where it sees no surface).
    """
    view: View
    depth: np.ndarray
    normal: np.ndarray


def surfaces(scene, before: Surfaces | None = None) -> tuple[Surfaces, FrameView | None]:
    """Trace the surfaces of the scene's view (one camera ray per pixel of its film) and where
    they were in the view `before`.

    Args:
        scene: the loaded `mi.Scene` at the draft's size (its first sensor is the view).
        before: the surfaces of the view shown before, or None (nothing to carry).

    Returns:
        (this view's `Surfaces`; the `FrameView` towards `before`'s pixels, or None where there
        is no `before` or its size differs: a resized view carries nothing).

    Raises:
        SceneError: a camera no pixel map projects (`View.of`: a spherical camera).
    """
    sensor = scene.sensors()[0]
    mine = View.of(sensor)
    towards = before is not None and before.view.size == mine.size
    # with no view before, the view itself is the previous one: the same kernel, traced once
    motion = Motion(previous=before.view if towards else mine, next=mine)
    out = render_data_passes(scene, ("depth", "normal", "vector"), spp=1, seed=SEED,
                             motion=motion)
    own = Surfaces(mine, out["depth"], out["normal"])
    if not towards:
        return own, None
    return own, FrameView.from_passes(out["depth"], out["normal"], out["vector"])


def carried(image: np.ndarray, before: Surfaces,
            view: FrameView) -> tuple[np.ndarray, np.ndarray]:
    """The image shown in the view `before`, carried to the view of `view` (module doc).

    Args:
        image: H' x W' x 3, the image on screen (any size: it is first brought to `before`'s size,
            `resampled`). before: the surfaces of the view it shows. view: the new view's pixels
            towards `before`'s (`surfaces`).

    Returns:
        (h x w x 3 float32 at the new view's draft size; h x w bool: where the pixel was carried,
        not filled).
    """
    w, h = before.view.size
    old = resampled(np.asarray(image, np.float64)[..., :3], w, h)
    ones = np.ones((h, w))
    history = Accumulated(old, np.zeros_like(old), ones, ones.astype(np.int64),
                          depth=before.depth, normal=before.normal)
    moved = reprojected(history, view)
    kept = moved.weight > 0
    return filled(moved.mean, kept).astype(np.float32), kept


def filled(image: np.ndarray, kept: np.ndarray) -> np.ndarray:
    """`image` with each pixel not `kept` set to the mean of the kept pixels in the smallest block
    around it that holds one (blocks of 2 x 2, 4 x 4, ... pixels on a grid: a push-pull fill, a
    few array operations per halving), so a disoccluded strip takes the colours next to it. Without
    any kept pixel, black.

    Args:
        image: H x W x C. kept: H x W bool.

    Returns:
        H x W x C float64 (the kept pixels' values unchanged).
    """
    img = np.asarray(image, np.float64)
    weight = kept.astype(np.float64)
    levels = [(img * weight[..., None], weight)]
    while max(levels[-1][1].shape) > 1:  # push: each level sums the 2 x 2 blocks of the one below
        total, weight = levels[-1]
        h, w = weight.shape
        pad = ((0, h % 2), (0, w % 2))
        total = np.pad(total, pad + ((0, 0),))
        weight = np.pad(weight, pad)
        h2, w2 = weight.shape[0] // 2, weight.shape[1] // 2
        levels.append((total.reshape(h2, 2, w2, 2, -1).sum(axis=(1, 3)),
                       weight.reshape(h2, 2, w2, 2).sum(axis=(1, 3))))
    value = np.zeros_like(levels[-1][0])
    for total, weight in reversed(levels):  # pull: a block without a kept pixel takes its parent's
        h, w = weight.shape
        up = np.repeat(np.repeat(value, 2, axis=0), 2, axis=1)[:h, :w]
        mean = total / np.maximum(weight, 1e-300)[..., None]
        value = np.where(weight[..., None] > 0, mean, up)
    return np.where(kept[..., None], img, value)


def resampled(image: np.ndarray, w: int, h: int) -> np.ndarray:
    """`image` at w x h: each new pixel the mean of the old pixels whose centres fall in it (a
    smaller size), or the old pixel its centre falls in (a larger one).

    Args:
        image: H x W x C. w, h: the new size.

    Returns:
        h x w x C float64 (`image` itself, as float64, at its own size).
    """
    img = np.asarray(image, np.float64)
    big_h, big_w = img.shape[:2]
    if (big_h, big_w) == (h, w):
        return img
    rows = np.minimum(((np.arange(big_h) + 0.5) * h / big_h).astype(np.int64), h - 1)
    cols = np.minimum(((np.arange(big_w) + 0.5) * w / big_w).astype(np.int64), w - 1)
    cell = (rows[:, None] * w + cols[None, :]).reshape(-1)
    flat = img.reshape(big_h * big_w, -1)
    count = np.bincount(cell, minlength=h * w)
    sums = np.stack([np.bincount(cell, flat[:, c], minlength=h * w)
                     for c in range(flat.shape[1])], -1)
    out = sums / np.maximum(count, 1)[:, None]
    empty = count == 0
    if empty.any():  # a larger size: the old pixel under the new pixel's centre
        ys = np.minimum(((np.arange(h) + 0.5) * big_h / h).astype(np.int64), big_h - 1)
        xs = np.minimum(((np.arange(w) + 0.5) * big_w / w).astype(np.int64), big_w - 1)
        out[empty] = img[ys][:, xs].reshape(h * w, -1)[empty]
    return out.reshape(h, w, -1)


__all__ = ["Surfaces", "surfaces", "carried", "filled", "resampled", "SEED"]
