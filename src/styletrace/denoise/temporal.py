"""Temporal reuse: the frames accumulate the estimate the denoiser meets, carried along the motion.

    history = History()
    for frame in frames:                       # each frame its own seed
        history.start(key, view)               # what the view is; where its surfaces were
        m = history.blend(m_frame, var, count)  # before OIDN
        d = history.hold(denoised(m))          # the value the style meets (expectation only)
        history.commit()                       # once the frame's result is final

What accumulates is the per-pixel estimate OIDN denoises: the expectation M at the stylized vertex
(`denoise.expectation.attach`), or the noisy image (`denoise.image.finish_denoised_image`). Frame
k of a still shot then meets an estimate of about k frames' samples, so its error against the
converged image falls with k, and what changes from one frame to the next shrinks as 1/k. The
frames are independent estimates of the same expectation (their seeds differ), so their weighted
mean is unbiased where the view is the same. With a `FrameView` (a frame's Depth, Normal and
Vector) the history is first carried to where each pixel's surface was (`reprojected`); a surface
seen for the first time starts afresh.

A key other than the last frame's starts the history again (Blender: every setting but the seed),
and that frame is exactly the frame without reuse. Within one key each pixel is also tested: where
the frame's 3 x 3 mean differs from the history's by more than Z standard errors in brightness (the
light or a material changed), the pixel starts again; a pixel without an estimate in a frame (no
stylized vertex: a light seen directly) keeps its history. The history's weight is capped at CAP
times the frame's, so a change the test misses fades within CAP frames. The frames of one view
share the seed of their guides and of the points where the style meets the estimate (`shared`),
and `hold` moves the shown value only beyond a margin of its error, so that a step style's edges
stay put. Design and measurements: docs/temporal.md.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

#: a pixel starts again where its 3 x 3 mean moved by more than Z standard errors (4: about 6e-5
#: of a still shot's pixels per frame by chance, Gaussian tails)
Z = 4.0
#: the history weighs at most CAP times the frame: a still shot converges over CAP frames
CAP = 255.0
#: a reprojected history pixel is kept where its depth is within DEPTH_TOLERANCE of the pixel's
#: (relative) and its normal within NORMAL_COSINE of it: a surface seen before, not one uncovered
DEPTH_TOLERANCE = 0.1
NORMAL_COSINE = 0.8
#: a pixel's shown value moves only by what its denoised value moved beyond HOLD standard errors
#: of the blended estimate (`History.hold`; chosen on the Cornell box, 8 frames of cel and
#: hatching, docs/temporal.md: 0.3 gave cel a mean change per frame of 0.21% against 0.96%
#: without, and an error at frame 8 1.4x that without)
HOLD = 0.3


@dataclass
class Accumulated:
    """The accumulated estimate of one view, per pixel.

    Args:
        mean: H x W x C, the weighted mean of the frames' estimates.
        var: H x W x C, its variance (NaN: unknown).
        weight: H x W, its weight (camera samples).
        frames: H x W, how many frames it holds.
        kept: H x W, where the frame continued the history (not started again).
        shown: H x W x C, the denoised value the frame showed (`History.hold`), or None.
        depth, normal: H x W and H x W x 3, what the frame's pixels saw (`FrameView`), for the
            next frame's reprojection; None without a view.
    """
    mean: np.ndarray
    var: np.ndarray
    weight: np.ndarray
    frames: np.ndarray
    kept: np.ndarray | None = None
    shown: np.ndarray | None = None
    depth: np.ndarray | None = None
    normal: np.ndarray | None = None


@dataclass(frozen=True)
class FrameView:
    """What each pixel of a frame sees, for reprojecting the history (`History.start`).

    Args:
        previous: H x W x 2, where the surface point the pixel sees was in the previous frame's
            image: (column, row) in pixels, the image's top left corner at (0, 0), pixel centres
            at +0.5 (from the Vector pass: `from_passes`).
        depth: H x W, the distance along the view axis to that point (the Depth pass).
        normal: H x W x 3, its world-space shading normal (the Normal pass).
    """
    previous: np.ndarray
    depth: np.ndarray
    normal: np.ndarray

    @classmethod
    def from_passes(cls, depth: np.ndarray, normal: np.ndarray,
                    vector: np.ndarray) -> "FrameView":
        """The view of a frame's data passes (`kernel.data_passes`, Blender's conventions: the
        vector's first two channels x_prev - x and y_prev - y in pixels, y up).

        Args:
            depth: H x W. normal: H x W x 3. vector: H x W x 4.

        Returns:
            The FrameView.
        """
        h, w = depth.shape
        cols, rows = np.meshgrid(np.arange(w) + 0.5, np.arange(h) + 0.5)
        previous = np.stack([cols + vector[..., 0], rows - vector[..., 1]], axis=-1)
        return cls(previous, np.asarray(depth, np.float64), np.asarray(normal, np.float64))


def box3(x: np.ndarray) -> np.ndarray:
    """The 3 x 3 mean of each pixel (edges repeated).

    Args:
        x: H x W or H x W x C.

    Returns:
        The same shape, float64.
    """
    pad = [(1, 1), (1, 1)] + [(0, 0)] * (x.ndim - 2)
    p = np.pad(np.asarray(x, np.float64), pad, mode="edge")
    h, w = x.shape[:2]
    return sum(p[dy:dy + h, dx:dx + w] for dy in range(3) for dx in range(3)) / 9.0


def local_variance(image: np.ndarray) -> np.ndarray:
    """A stand-in for a pixel's variance where its samples' spread is not known: the variance of
    its 3 x 3 neighbourhood. The image's own variation counts as noise, so the test of `History`
    is looser there (it starts pixels again less often), never stricter.

    Args:
        image: H x W x C.

    Returns:
        H x W x C float64.
    """
    mean = box3(image)
    return np.maximum(box3(np.asarray(image, np.float64) ** 2) - mean * mean, 0.0)


class History:
    """The accumulated estimate of the frames of one view (module doc).

    Args:
        cap: the history's most weight, in multiples of a frame's (CAP).
        z: the per-pixel test's threshold, in standard errors (Z).
        hold: `hold`'s margin, in standard errors of the blended estimate (HOLD; 0: none).

    Raises:
        ValueError: cap < 0, z <= 0 or hold < 0.
    """

    def __init__(self, cap: float = CAP, z: float = Z, hold: float = HOLD):
        if not cap >= 0:
            raise ValueError(f"bad history cap {cap!r}: expected a number >= 0")
        if not z > 0:
            raise ValueError(f"bad history threshold {z!r}: expected a number > 0")
        if not hold >= 0:
            raise ValueError(f"bad history hold {hold!r}: expected a number >= 0")
        self.cap, self.z, self.margin = float(cap), float(z), float(hold)
        self.key: Any = None
        self.state: Accumulated | None = None
        self._pending: Accumulated | None = None
        self._shared: dict = {}
        self._view: FrameView | None = None

    def start(self, key: Any, view: FrameView | None = None) -> bool:
        """Begin a frame of the view `key`: a key other than the last frame's forgets the
        history; with `view`, the history is carried to where this frame sees its surfaces
        (`reprojected`), and this frame's depths and normals are kept for the next.

        Args:
            key: what the view is (anything comparable with ==).
            view: this frame's `FrameView`, or None: the camera and the scene stand still.

        Returns:
            Whether the frame has a history to blend with.
        """
        if key != self.key:
            self.key, self.state, self._shared = key, None, {}
        if view is not None and self.state is not None and self.state.depth is not None:
            self.state = reprojected(self.state, view)
        self._view = view
        self._pending = None
        return self.state is not None

    def shared(self, name: str, value: Any) -> Any:
        """A value the frames of one view share: the first frame's `value` of `name`, kept until
        the view changes (the seed of the points where a style meets the estimate: points that
        stay put from frame to frame leave only the estimate to change).

        Args:
            name: what the value is. value: this frame's.

        Returns:
            The view's value.
        """
        return self._shared.setdefault(name, value)

    def blend(self, m: np.ndarray, var: np.ndarray | None, count) -> np.ndarray:
        """This frame's estimate merged with the history (nothing kept until `commit`).

        Args:
            m: H x W x C, the frame's estimate. var: its variance per pixel, the same shape (NaN
                or None: unknown, `local_variance` of m stands in). count: its weight, a number
                or H x W (0: no estimate in that pixel: the history's value, else the frame's).

        Returns:
            H x W x C float32: m itself (its values, bit for bit) where the history starts
            again, the weighted mean where it goes on, the history's mean where the frame has
            no estimate.
        """
        m = np.asarray(m)
        shape = m.shape[:2]
        c = np.broadcast_to(np.asarray(count, np.float64), shape)
        v = None if var is None else np.asarray(var, np.float64)
        if v is None or not np.isfinite(v).all():  # the stand-in, made once where it is needed
            local = local_variance(m)
            v = local if v is None else np.where(np.isfinite(v), v, local)
        s = self.state
        if s is None or s.mean.shape != m.shape:
            self._pending = Accumulated(m.astype(np.float64), v, c.copy(),
                                        (c > 0).astype(np.int64), np.zeros(shape, bool),
                                        **self._surfaces())
            return np.array(m, dtype=np.float32, copy=True)
        valid = (c > 0) & (s.weight > 0)
        keep = valid & ~self.changed(m, v, s, valid)
        restart = (c > 0) & ~keep  # a pixel without an estimate this frame keeps its history
        w_h = np.where(keep, np.minimum(s.weight, self.cap * c), 0.0)
        total = w_h + c
        safe = np.where(total > 0, total, 1.0)[..., None]  # total 0: no estimate, m kept
        mean = (w_h[..., None] * s.mean + c[..., None] * m) / safe
        var_out = (w_h[..., None] ** 2 * s.var + c[..., None] ** 2 * v) / safe ** 2
        # a pixel without an estimate this frame (its samples found no vertex, a frame's chance at
        # an edge of the view) shows its history's
        idle = (c <= 0) & (s.weight > 0)
        out = np.where(keep[..., None], mean, np.where(idle[..., None], s.mean, m))
        self._pending = Accumulated(
            np.where(keep[..., None], mean, np.where(restart[..., None], m, s.mean)),
            np.where(keep[..., None], var_out, np.where(restart[..., None], v, s.var)),
            np.where(keep | restart, total, s.weight),
            np.where(keep, s.frames + 1, np.where(restart, 1, s.frames)),
            keep | idle, **self._surfaces())
        return out.astype(np.float32)

    def _surfaces(self) -> dict:
        """This frame's depths and normals, for the next frame's reprojection (none without a
        view)."""
        v = self._view
        return {} if v is None else {"depth": v.depth, "normal": v.normal}

    def hold(self, d: np.ndarray) -> np.ndarray:
        """The value a frame shows (after `blend`): the last frame's shown value, moved towards
        this frame's denoised one by what that moved beyond a margin of `hold` standard errors of
        the blended estimate (in brightness; the variance's 3 x 3 mean), where the pixel
        continued its history. A step style's decision near a threshold then changes when the
        estimate has moved, not with every frame's noise, and neighbouring pixels move together
        (a soft dead zone: an edge stays as smooth as the denoiser made it). The margin falls as
        the frames accumulate, so a still shot still converges; where the history started again
        the value is the frame's own.

        Args:
            d: H x W x C, the denoised estimate (or image) of this frame.

        Returns:
            H x W x C float32.
        """
        d = np.asarray(d, np.float32)
        p, s = self._pending, self.state
        if p is None:
            return d
        out = d
        if (s is not None and s.shown is not None and s.shown.shape == d.shape
                and p.kept is not None and self.margin > 0):
            # the margin from the 3 x 3 mean of the variance, and a soft dead zone: the shown
            # value moves by what the new one moved beyond the margin, so neighbouring pixels
            # move together and an edge stays as smooth as the denoiser made it
            margin = self.margin * np.sqrt(box3(np.nan_to_num(p.var.mean(axis=-1), nan=0.0)))
            delta = d - s.shown
            moved = np.abs(delta.mean(axis=-1))
            share = np.where(moved > margin, 1.0 - margin / np.maximum(moved, 1e-30), 0.0)
            share = np.where(p.kept, share, 1.0)
            out = (s.shown + share[..., None] * delta).astype(np.float32)
        p.shown = out
        return out

    def changed(self, m: np.ndarray, var: np.ndarray, s: Accumulated,
                valid: np.ndarray) -> np.ndarray:
        """Where the brightness of the frame's 3 x 3 neighbourhood differs from the history's by
        more than z standard errors (over the neighbours where both have an estimate; the
        channels' variances averaged, as if fully correlated: grey light).

        Args:
            m, var: the frame's estimate and variance (H x W x C). s: the history.
            valid: H x W, where both have an estimate.

        Returns:
            H x W bool.
        """
        diff = np.where(valid, (m - s.mean).mean(axis=-1), 0.0)
        v = np.where(valid, (var + np.nan_to_num(s.var, nan=np.inf)).mean(axis=-1), 0.0)
        n = np.maximum(box3(valid) * 9.0, 1.0)
        d = box3(diff) * 9.0 / n
        se2 = box3(v) * 9.0 / (n * n)
        return valid & (d * d > self.z * self.z * se2)

    def commit(self) -> None:
        """Keep what the last `blend` made: the next frame blends with it."""
        if self._pending is not None:
            self.state, self._pending = self._pending, None

    @property
    def frames(self) -> np.ndarray | None:
        """How many frames each pixel's history holds (None before the first commit)."""
        return None if self.state is None else self.state.frames


def reprojected(s: Accumulated, view: FrameView) -> Accumulated:
    """The history `s` of the previous frame carried to this frame's pixels: each pixel takes
    the bilinear mean of the four history pixels around where its surface was (`view.previous`),
    over those that saw the same surface (depth within DEPTH_TOLERANCE, normal within
    NORMAL_COSINE of the pixel's); a pixel with none (its surface uncovered, or outside the last
    image) gets no history (weight 0: it starts again). The variance is the neighbours' weighted
    mean (an upper bound of the mean's), the weight their weighted mean.

    Args:
        s: the previous frame's history (with its depths and normals). view: this frame's.

    Returns:
        The history on this frame's pixels (its `shown` carried too; `kept` all False; the
        depths and normals this frame's).
    """
    h, w = s.weight.shape
    x = view.previous[..., 0] - 0.5
    y = view.previous[..., 1] - 0.5
    x0, y0 = np.floor(x).astype(np.int64), np.floor(y).astype(np.int64)
    fx, fy = x - x0, y - y0
    # every field in one array, so that each corner gathers once (the arithmetic per channel is
    # the same as field by field)
    parts = [s.mean, s.var, s.weight[..., None], s.frames[..., None].astype(np.float64)]
    if s.shown is not None:
        parts.append(s.shown)
    sizes = [p.shape[-1] for p in parts]
    table = np.concatenate(parts, axis=-1).reshape(h * w, -1)
    depths, normals, weights = s.depth.ravel(), s.normal.reshape(h * w, 3), s.weight.ravel()
    total = np.zeros((h, w))
    acc = np.zeros((h, w, table.shape[1]))
    corners = ((0, 0, (1 - fx) * (1 - fy)), (1, 0, fx * (1 - fy)), (0, 1, (1 - fx) * fy),
               (1, 1, fx * fy))
    if not (fx.any() or fy.any()):  # every surface where it was: only the pixel itself weighs
        corners = corners[:1]
    for dx, dy, corner in corners:
        xi, yi = x0 + dx, y0 + dy
        inside = (xi >= 0) & (xi < w) & (yi >= 0) & (yi < h)
        at = np.clip(yi, 0, h - 1) * w + np.clip(xi, 0, w - 1)
        same = (np.abs(depths[at] - view.depth) <= DEPTH_TOLERANCE * np.abs(view.depth)) & (
            np.sum(normals[at] * view.normal, axis=-1) >= NORMAL_COSINE)
        ok = inside & same & (weights[at] > 0) & (corner > 0)
        c = np.where(ok, corner, 0.0)
        total += c
        acc += c[..., None] * table[at]
    found = total > 1e-6
    acc /= np.where(found, total, 1.0)[..., None]
    mean, var, weight, frames, *shown = np.split(acc, np.cumsum(sizes)[:-1], axis=-1)
    weight = np.where(found, weight[..., 0], 0.0)
    frames = np.where(found, np.rint(frames[..., 0]), 0).astype(np.int64)
    return Accumulated(mean, var, weight, frames, np.zeros((h, w), bool),
                       shown[0] if shown else None, view.depth, view.normal)


__all__ = ["History", "Accumulated", "FrameView", "reprojected", "box3", "local_variance", "Z",
           "CAP", "HOLD", "DEPTH_TOLERANCE", "NORMAL_COSINE"]
