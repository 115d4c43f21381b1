"""reuse_deep=world: the second stylized level pools too, with world-space neighbours (Tong and
Hachisuka's path filtering; first_n_hits with N = 2 only).

All children of a batch are drawn at once, one lane each (child j of lane i at i * M + j): a
delta-light sample and a BSDF sample from the first hit, as `bounce.bounce`. The level-1 vertices
they reach (one per child) draw m2 children each (reuse_children.draw: ordinary paths beyond the
last level), and each pools with the accepted ones of K2 candidates from its jittered cell of a
world-space grid (world_grid.py: same target, BSDF and normal, within distance h), with the weights
of reuse_pool.py; g of that pooled value is the child's Li.
"""
from __future__ import annotations

import numpy as np

from styletrace.config import settings as S
from styletrace.gate import dr, mi
from styletrace.kernel import reuse_pool as P
from styletrace.kernel.lane_sampler import LaneSampler
from styletrace.kernel.reuse_children import Children, Draw, Parents, Slab, Span, draw
from styletrace.kernel.reuse_scope import children_per_lane, first_round, slots, styled_value
from styletrace.kernel.vertex import emission
from styletrace.kernel.world_grid import WorldGrid, density_h
from styletrace.styles.base import Vertex


def level1(scope, lanes, parents: Parents, m, slab: Slab):
    """`reuse_children.draw` for first_n_hits at depth 2 with the second level pooled too: every
    drawing lane's m children at once, one lane each, their second-level vertices shaded together
    by `level2`, whose value is the child's Li.

    Args:
        scope, lanes: the render's Scope and the lanes' random streams.
        parents: the first hits (its `active` lanes draw). m: each lane's count (mi.UInt32).
        slab: where the children are stored (child j of lane i at i * M + j).

    Returns:
        Per lane, the sum of its children's ordinary estimates (mi.Spectrum).
    """
    scene, M, kids = scope.scene, slab.M, slab.kids
    si, bsdf = parents.si, parents.bsdf
    N = dr.width(si.p)
    idx = dr.arange(mi.UInt32, N * M)
    owner, j = idx // M, idx % M
    on = dr.gather(mi.Bool, parents.active, owner) & (j < dr.gather(mi.UInt32, m, owner))
    # one PCG32 stream per child, seeded from its camera sample's own stream
    hi = dr.gather(mi.UInt32, dr.reinterpret_array(mi.UInt32, lanes.next_1d()), owner)
    lo = dr.gather(mi.UInt32, dr.reinterpret_array(mi.UInt32, lanes.next_1d()), owner)
    smp = LaneSampler(mi.PCG32(N * M, initstate=(mi.UInt64(hi) << 32) | mi.UInt64(lo),
                               initseq=dr.arange(mi.UInt64, N * M)))
    c = Draw(
        scope,
        smp,
        Parents(
            dr.gather(mi.SurfaceInteraction3f, si, owner),
            dr.gather(mi.BSDFPtr, bsdf, owner),
            on,
            mi.Bool(True),
        ),
        on,
        0,
        nested=True,
    )
    si2, hit2 = c.next_vertex()
    x = c.store(kids, idx, c.seen(scene, si2, hit2, level2(scope, smp, si2, c.ray2, hit2)), on)
    lane = dr.arange(mi.UInt32, N)
    total = mi.Spectrum(0.0)
    for k in range(M):  # in a fixed order (a scatter-add would not be bit-reproducible)
        total += dr.gather(mi.Spectrum, x, lane * M + k)
    return total


def level2(scope, smp, si, ray, hit):
    """The stylized value of second-level vertices that pool the children of their world-space
    neighbours (world_grid.py): m2 children each by `reuse_children.draw` (ordinary paths beyond
    the last stylized level), pooled exactly as at the first hit, then g of the vertex's slot.

    Args:
        scope, smp: the render's Scope and the children's random streams (one per lane).
        si, ray: the vertices and the rays that reached them. hit: the lanes at a surface.

    Returns:
        mi.Spectrum, 0 where no target applies.
    """
    s, scene, keep = scope.settings, scope.scene, scope.keep
    bsdf = si.bsdf(ray)
    lanes = slots(scope, si, hit, bsdf, 1)
    target, m, pool = lanes.target, lanes.m, lanes.pool
    M = children_per_lane(scope.targets, 1)
    slab = Slab(Children(dr.width(si.p) * M), M)
    base = emission(scene, si, hit)
    J = first_round(scope.targets, 1)
    own = draw(scope, smp, Parents(si, bsdf, hit & (m > 0), pool),
               Span(mi.UInt32(0), m, J, slab, dr.arange(mi.UInt32, dr.width(si.p))), depth=1)
    jitter, start = mi.Point3f(smp.next_1d(), smp.next_1d(), smp.next_1d()), smp.next_1d()
    n = mi.Vector3f(si.sh_frame.n)
    dr.eval(slab.kids, own, base, si, target, m, pool, jitter, start, bsdf, smp)
    box = scene.bbox()
    diag = float(dr.norm(box.extents()))
    h = (
        s.reuse_h * diag
        if s.reuse_h > 0
        else density_h(si.p, pool, s.reuse_k2, box.min, S.MIN_REUSE_H * diag, diag)
    )
    grid = WorldGrid(si.p, pool, h, s.reuse_k2, jitter, start, box.min)
    mask = grid.accepted(target, bsdf, pool, n, P.NORMAL_MIN)
    dr.eval(mask)
    if keep is not None:
        keep.update(
            world_mask=np.asarray(mask, dtype=np.uint64),
            world_p=np.asarray(si.p, dtype=np.float64),
            world_pool=np.asarray(pool, dtype=bool),
            world_h=grid.h,
            world_k=grid.K,
            world_order=np.asarray(grid.order),
            world_first=np.asarray(grid.first),
            world_count=np.asarray(grid.count),
            world_offset=np.asarray(grid.offset),
        )
    mean = P.pooled(P.Pools(grid, mask, si, bsdf, m), slab, J, scope.weights)
    mean = dr.select(pool, mean, own / mi.Float(dr.maximum(m, 1)))
    v = Vertex(p=si.p, n=n, wo=-ray.d, view=mi.Vector3f(scope.view), depth=mi.UInt32(1))
    return styled_value(scope, target, base + mean, v, 0.0)
