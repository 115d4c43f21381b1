"""Which candidate neighbours a stored vertex may pool with (reuse=pixels): one test for both
neighbour grids.

A candidate in slot q (slot 0: the vertex itself) is accepted when it exists, both may pool, and it
has the same style target, the same BSDF object and a shading normal within `normal_min` (n.n'); the
grid adds its own geometric test (`near`): camera distances for the pixel window (reuse_pool.Grid),
world distance for the world grid (world_grid.WorldGrid). The result is one bit per slot, K + 1
slots in a UInt64 (K <= 63).
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from styletrace.gate import dr, mi


@dataclass
class Candidates:
    """Per vertex what acceptance compares.

    Args:
        target: the style target (mi.Int32). bsdf: the BSDF (mi.BSDFPtr).
        pool: whether it may pool (mi.Bool). n: the shading normal (mi.Vector3f).
    """

    target: Any
    bsdf: Any
    pool: Any
    n: Any


def accepted(
    neighbour, K: int, c: Candidates, normal_min: float, near, label: str
) -> mi.UInt64:
    """Bit q set where slot q's vertex may be pooled with the vertex's own.

    Args:
        neighbour: neighbour(q) -> (index mi.UInt32, exists mi.Bool) of slot q (0: the vertex).
        K, normal_min: the candidate slots 1 .. K (K <= 63); the least n.n' accepted.
        c: the vertices' `Candidates`, indexed by `neighbour`'s indices.
        near: near(at, ok) -> mi.Bool, the grid's geometric test of the candidates at `at`.
        label: the traced loop's name.

    Returns:
        mi.UInt64, one bit per slot 0 .. K.
    """
    target, bsdf, pool, n = c.target, c.bsdf, c.pool, c.n

    def body(q, mask):
        at, found = neighbour(q)
        ok = found & pool & dr.gather(mi.Bool, pool, at, found)
        ok &= dr.gather(mi.Int32, target, at, ok) == target
        ok &= dr.gather(mi.BSDFPtr, bsdf, at, ok) == bsdf
        ok &= dr.dot(dr.gather(mi.Vector3f, n, at, ok), n) > normal_min
        ok &= near(at, ok)
        mask |= dr.select(ok, mi.UInt64(1) << mi.UInt64(q), mi.UInt64(0))
        return q + 1, mask

    _, mask = dr.while_loop((mi.UInt32(0), mi.UInt64(0)), lambda q, mask: q <= K, body, label=label)
    return mask
