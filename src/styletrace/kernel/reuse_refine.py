"""The refinement round of adaptive counts n0:n_max at the first hit (reuse=pixels).

Lanes draw n0 children and pool them; the lanes whose pooled mean AdaptiveDirect's rule finds too
close to a style threshold (or too curved), told the pool's C = sum_P c_k samples and their second
moment, draw n_max - n0 more and recompute their pools with every member's children: direct / C;
balance with Veach's multi-sample weights with per-member counts c_k, 1 / sum_k c_k p_k; pairwise by
layers, one per child index j over the members with c_k > j, averaged with weights |P_j| /
C (reuse_pool.py).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from styletrace.config.estimator_registry import adaptive_direct
from styletrace.estimators import channel_mean
from styletrace.gate import dr, mi
from styletrace.kernel.lane_sampler import LaneSampler
from styletrace.kernel.reuse_children import Parents, Slab, Span, draw
from styletrace.kernel.reuse_pool import Grid, Pools, pooled
from styletrace.kernel.reuse_scope import Slots, most, refined


@dataclass(frozen=True)
class Round:
    """The first round's pooled result per lane: what g adds it to (`base`: emission at v), the
    pooled mean, the moments s1 = sum u_i and s2 = sum u_i^2 of its children's brightness, and their
    count C."""
    base: mi.Spectrum
    mean: mi.Spectrum
    s1: mi.Float
    s2: mi.Float
    C: mi.Float


def refine_pools(scope, lanes, first: Pools, slots: Slots, slab: Slab, v, done: Round):
    """The pooling lanes whose first-round pooled mean the style's rule (AdaptiveDirect.needs_more,
    told the pool's C samples and their moments) finds too close to a threshold, or too curved,
    draw n_max - n0 more children (those lanes alone, compacted) and recompute their pools.

    Args:
        scope, lanes: the render's Scope and the lanes' random streams.
        first, slots, slab: the first round's pools, the lanes' Slots and the stored children.
        v: the lanes' style Vertex. done: the first round's pooled result.

    Returns:
        (pooled mean mi.Spectrum, children per lane mi.UInt32).
    """
    s, keep, targets = scope.settings, scope.keep, scope.targets
    target, m, pool = slots.target, slots.m, slots.pool
    mean, s1, s2, C = done.mean, done.s1, done.s2, done.C
    which = refined(targets)
    # one kernel for the first round's pool (each output traced alone re-runs the loop)
    dr.eval(mean, s1, s2, C)
    x = done.base + mean
    state = {"count": C, "sum": x * C, "mean_u": channel_mean(x),
             "m2_u": dr.maximum(s2 - dr.square(s1) / dr.maximum(C, 1.0), 0.0)}
    flag, n_max = mi.Bool(False), mi.UInt32(m)
    for i in which:
        slot = targets[i].slot
        est = adaptive_direct(
            slot.style, int(slot.n(0)), most(slot.n(0)), v, s.adaptive_z, s.adaptive_bias
        )
        state["tau"] = tuple(dr.zeros(mi.Float, dr.width(C)) + t for t in est.thresholds)
        here = (target == i) & pool
        flag |= here & est.needs_more(state)
        n_max = dr.select(here, most(slot.n(0)), n_max)
    dr.eval(flag, n_max)
    idx = dr.compress(flag)
    count = dr.select(flag, n_max, m)
    if keep is not None:
        keep.update(
            flag=np.asarray(flag),
            mean_u=np.asarray(state["mean_u"]),
            m2_u=np.asarray(state["m2_u"]),
            count=np.asarray(C),
        )
    if dr.width(idx) == 0:
        return mean, count
    more = max(most(targets[i].slot.n(0)) - int(targets[i].slot.n(0)) for i in which)
    _draw_more(scope, lanes, first, slab, idx, (m, n_max, more))
    si, bsdf, grid = first.si, first.bsdf, first.grid
    si_k, bsdf_k = dr.gather(mi.SurfaceInteraction3f, si, idx), dr.gather(mi.BSDFPtr, bsdf, idx)
    dr.eval(slab.kids, count)
    sub_grid = Grid(
        grid.frame, grid.radius, grid.K, dr.gather(mi.UInt32, grid.start, idx), lane=idx
    )
    again = pooled(
        Pools(
            sub_grid,
            dr.gather(mi.UInt64, first.mask, idx),
            si_k,
            bsdf_k,
            count,
            si_all=si,
            equal=False,
        ),
        slab,
        slab.M,
        scope.weights,
    )
    mean = mi.Spectrum(mean)
    dr.eval(mean)
    dr.scatter(mean, again, idx)
    return mean, count


def _draw_more(scope, lanes, first: Pools, slab: Slab, idx, counts):
    """The extra children of the flagged lanes `idx` (counts: m, n_max per lane and the most extra
    children), one lane each (flagged lane x extra child: wide and loop-free), each on its own
    random stream: the flagged lane's state, a stream index per extra child."""
    m, n_max, more = counts
    f = dr.arange(mi.UInt32, dr.width(idx) * more)
    at = dr.gather(mi.UInt32, idx, f // more)
    sub = LaneSampler(mi.PCG32(dr.width(f), initstate=dr.gather(mi.UInt64, lanes.rng.state, at),
                               initseq=mi.UInt64(f)))
    parents = Parents(
        dr.gather(mi.SurfaceInteraction3f, first.si, at),
        dr.gather(mi.BSDFPtr, first.bsdf, at),
        mi.Bool(True),
        mi.Bool(True),
    )
    draw(
        scope,
        sub,
        parents,
        Span(dr.gather(mi.UInt32, m, at) + f % more, dr.gather(mi.UInt32, n_max, at), 1, slab, at),
    )
