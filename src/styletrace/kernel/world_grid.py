"""World-space neighbours of stored path vertices for reuse=pixels at the second stylized level.

A uniform grid of cell size h over the scene's bounding box, built on the host with numpy (packed
cell keys, a stable argsort, a binary search per lookup: the same neighbours on any thread count).
A vertex looks up the cell of its position jittered by up to h/2 on each axis, takes K consecutive
candidates of that cell from a random start, itself excluded, and accepts those within distance h
with the same style target and BSDF object and n.n' > normal_min. `neighbour(q)` and `accepted`
mean what `reuse_pool.Grid`'s do, so `reuse_pool.pooled` pools over either.
Design: docs/design/world_grid.md.
"""
from __future__ import annotations

import numpy as np

from styletrace.gate import dr, mi
from styletrace.kernel.acceptance import Candidates, accepted

#: bits per axis in a packed cell key (cells per axis are bounded by settings.MIN_REUSE_H)
AXIS_BITS = 21


def uint32(a: np.ndarray) -> mi.UInt32:
    """A numpy array as a Dr.Jit array in Dr.Jit's own (aligned) memory: a kernel reading numpy's
    memory directly is compiled for its alignment, so the large kernels that read these would be
    compiled anew (about a second) whenever numpy's allocation is aligned otherwise.

    Args:
        a: integers that fit 32 bits.

    Returns:
        mi.UInt32, evaluated.
    """
    # a tiny kernel's output, in Dr.Jit's memory
    out = mi.UInt32(a.astype(np.uint32)) + dr.opaque(mi.UInt32, 0)
    dr.eval(out)
    return out


def cell_keys(P: np.ndarray, corner: np.ndarray, h: float) -> np.ndarray:
    """One int64 per column of P: its cell of size h above `corner`, packed (AXIS_BITS per axis).

    Args:
        P: points, shape (3, n). corner: shape (3, 1), below every point. h: the cell size.

    Returns:
        int64 array of shape (n,).
    """
    cell = np.clip(np.floor((P - corner) / h), 0, (1 << AXIS_BITS) - 1).astype(np.int64)
    return (cell[0] << (2 * AXIS_BITS)) | (cell[1] << AXIS_BITS) | cell[2]


def density_h(
    p: mi.Point3f, valid: mi.Bool, K: int, corner, low: float, high: float, rounds: int = 4
) -> float:
    """The cell size at which a vertex's own cell holds about K + 1 of the `valid` vertices (itself
    included), averaged over them; each round rescales h by sqrt((K + 1) / count) (path vertices
    lie on surfaces: a cell's count grows as h^2), starting from `high` split evenly.

    Args:
        p, valid: the vertices (mi.Point3f) and those that count (mi.Bool).
        K: the candidates wanted per vertex. corner: a corner below every vertex.
        low, high: the bounds of h; `high` is the bounding box's diagonal.
        rounds: rescaling rounds.

    Returns:
        h (world units); `high` where fewer than 2 vertices count.
    """
    P = np.asarray(p, dtype=np.float64).reshape(3, -1)[:, np.asarray(valid, dtype=bool)]
    if P.shape[1] < 2:
        return high
    corner = np.asarray(corner, dtype=np.float64).reshape(3, 1)
    h = float(np.clip(high * np.sqrt((K + 1) / P.shape[1]), low, high))
    for _ in range(rounds):
        _, inverse, counts = np.unique(
            cell_keys(P, corner, h), return_inverse=True, return_counts=True
        )
        h = float(np.clip(h * np.sqrt((K + 1) / counts[inverse].mean()), low, high))
    return h


class WorldGrid:
    """Slot 0 is the vertex itself, slot q >= 1 the q-th candidate of its jittered cell (module
    docstring).

    Args:
        p: the vertices (mi.Point3f). valid: those that may be found (mi.Bool).
        h: the cell size and the acceptance radius (world units).
        K: candidate slots per vertex.
        jitter: per vertex its lookup's offset, in [0, 1)^3 of a cell (mi.Point3f).
        start: per vertex its first candidate, in [0, 1) of its cell's count (mi.Float).
        origin: a corner below every vertex (the scene's bounding box's minimum).
    """

    def __init__(
        self,
        p: mi.Point3f,
        valid: mi.Bool,
        h: float,
        K: int,
        jitter: mi.Point3f,
        start: mi.Float,
        origin,
    ):
        self.h, self.K = float(h), K
        self.p = p
        width = dr.width(p)
        self.lane = dr.arange(mi.UInt32, width)
        # a jittered lookup stays above it
        corner = np.asarray(origin, dtype=np.float64).reshape(3, 1) - h
        P = np.asarray(p, dtype=np.float64).reshape(3, width)
        keys = self.keys(P, corner)
        keys[~np.asarray(valid, dtype=bool)] = np.iinfo(np.int64).max   # never found
        order = np.argsort(keys, kind="stable")
        sorted_keys = keys[order]
        Q = P + (np.asarray(jitter, dtype=np.float64).reshape(3, width) - 0.5) * h
        q = self.keys(Q, corner)
        first = np.searchsorted(sorted_keys, q, side="left")
        count = np.searchsorted(sorted_keys, q, side="right") - first
        offset = np.minimum(
            (np.asarray(start, dtype=np.float64) * count).astype(np.int64), np.maximum(count - 1, 0)
        )
        self.order, self.first, self.count, self.offset = (
            uint32(a) for a in (order, first, count, offset)
        )

    def keys(self, P: np.ndarray, corner: np.ndarray) -> np.ndarray:
        """`cell_keys` with this grid's h.

        Args:
            P: points, shape (3, n). corner: shape (3, 1), below every point.

        Returns:
            int64 array of shape (n,).
        """
        return cell_keys(P, corner, self.h)

    def neighbour(self, q):
        """(vertex index, a candidate exists) of slot q.

        Args:
            q: the slot (mi.UInt32), 0 .. K.

        Returns:
            (mi.UInt32 index, the vertex itself where none; mi.Bool).
        """
        first = q == 0
        k = q - 1
        ok = ~first & (k < self.count)
        at = dr.gather(
            mi.UInt32, self.order, self.first + (self.offset + k) % dr.maximum(self.count, 1), ok
        )
        ok &= at != self.lane
        return dr.select(ok, at, self.lane), first | ok

    def accepted(self, target, bsdf, pool, n, normal_min) -> mi.UInt64:
        """Bit q set where slot q's vertex may be pooled with the vertex's own (acceptance.py),
        within distance h.

        Args:
            target, bsdf, pool, n: per vertex its style target (mi.Int32), BSDF (mi.BSDFPtr),
                whether it may pool (mi.Bool) and shading normal (mi.Vector3f).
            normal_min: the least n.n' accepted.

        Returns:
            mi.UInt64, one bit per slot 0 .. K.
        """
        # not a literal: h changes from pass to pass, the kernel not
        h2 = dr.opaque(mi.Float, self.h * self.h)

        def near(at, ok):
            return dr.squared_norm(dr.gather(mi.Point3f, self.p, at, ok) - self.p) <= h2
        return accepted(self.neighbour, self.K, Candidates(target, bsdf, pool, n), normal_min, near,
                        "styletrace reuse world accept")
