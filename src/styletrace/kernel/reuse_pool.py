"""Pooling: the pixel window of neighbours, and the pooled estimate of each vertex from its
members' children.

The pool P(v) is v and its accepted neighbours among K drawn from the (2r+1)^2 pixel window (same
sample index): same style target and BSDF object, n.n' > NORMAL_MIN, camera distances within
DEPTH_TOL. With v's own BSDF f_v (cosine included), over the C = sum_P c_k children of the pool,

    direct(v)   = 1/C sum_{k in P} sum_j f_v(wl_kj) E_kj      (neighbours' visibility reused)
    indirect(v) = sum_{k in P} sum_j f_v(wb_kj) Li_kj w_k(wb_kj)

w_k: balance, 1 / sum_k c_k p_k; pairwise (`_pairwise`); 'own', 1 / (C p_k), the negative control.
Design: docs/design/sample_reuse.md.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from styletrace.estimators import channel_mean
from styletrace.gate import dr, mi
from styletrace.kernel.acceptance import Candidates, accepted

#: acceptance of a neighbour: shading normals within about 25 degrees, camera distances within
#: 5 percent
NORMAL_MIN = 0.9
DEPTH_TOL = 0.05


def window(radius: int) -> np.ndarray:
    """The (2r+1)^2 - 1 pixel offsets around a pixel (itself excluded) in a fixed shuffled order: a
    lane takes K consecutive ones from a random start, so each offset is pooled with probability K
    / len.

    Args:
        radius: r, in pixels.

    Returns:
        int32 array of shape (W, 2): (dx, dy) per offset.
    """
    offsets = [
        (dx, dy)
        for dy in range(-radius, radius + 1)
        for dx in range(-radius, radius + 1)
        if dx or dy
    ]
    order = np.random.default_rng(0x5EED).permutation(len(offsets))
    return np.array([offsets[i] for i in order], dtype=np.int32)


@dataclass(frozen=True)
class Frame:
    """The pass's lanes: width x height pixels of spp samples each (lane = pixel * spp +
    sample index)."""
    width: int
    height: int
    spp: int


class Grid:
    """The neighbour slots of each lane: slot 0 is the lane itself, slot q >= 1 the pixel at window
    offset order[(start + q - 1) mod W], same sample index.

    Args:
        frame: the pass's lanes (width x height pixels of spp samples each).
        radius: the window's radius r in pixels (W = (2r+1)^2 - 1 offsets, `window`).
        K: candidate slots per lane (at most W and 63).
        start: per served lane, its first window offset (mi.UInt32 in [0, W)).
        lane: the lanes (indices into the pass) this grid serves (mi.UInt32); None: all of them.
    """

    def __init__(self, frame: Frame, radius, K, start, lane=None):
        width, height, spp = frame.width, frame.height, frame.spp
        self.frame = frame
        self.width, self.height, self.spp, self.K, self.radius = width, height, spp, K, radius
        offsets = window(radius)
        self.W = len(offsets)
        self.dx, self.dy = mi.Int32(offsets[:, 0]), mi.Int32(offsets[:, 1])
        self.start = start
        self.lane = dr.arange(mi.UInt32, width * height * spp) if lane is None else lane
        pix = self.lane // spp
        self.s = self.lane - pix * spp
        self.y = mi.Int32(pix // width)
        self.x = mi.Int32(pix) - self.y * width

    def neighbour(self, q):
        """(lane index, inside the image) of slot q.

        Args:
            q: the slot (mi.UInt32), 0 .. K.

        Returns:
            (mi.UInt32 lane index in the pass, the lane itself where outside; mi.Bool).
        """
        o = (self.start + q - 1) % self.W
        first = q == 0
        x = self.x + dr.select(first, 0, dr.gather(mi.Int32, self.dx, o, ~first))
        y = self.y + dr.select(first, 0, dr.gather(mi.Int32, self.dy, o, ~first))
        inside = (x >= 0) & (x < self.width) & (y >= 0) & (y < self.height)
        at = (
            mi.UInt32(dr.maximum(y, 0)) * self.width + mi.UInt32(dr.maximum(x, 0))
        ) * self.spp + self.s
        return dr.select(inside, at, self.lane), inside

    def accepted(self, target, bsdf, pool, n, depth) -> mi.UInt64:
        """Bit q set where slot q's vertex may be pooled with the lane's own (acceptance.py), camera
        distances within DEPTH_TOL.

        Args:
            target, bsdf, pool, n: per lane of the pass its style target (mi.Int32), BSDF
                (mi.BSDFPtr), whether it may pool (mi.Bool) and shading normal (mi.Vector3f).
            depth: per lane of the pass its camera distance (mi.Float, world units).

        Returns:
            mi.UInt64, one bit per slot 0 .. K.
        """
        def near(at, ok):
            return dr.abs(dr.gather(mi.Float, depth, at, ok) - depth) <= DEPTH_TOL * depth

        return accepted(
            self.neighbour,
            self.K,
            Candidates(target, bsdf, pool, n),
            NORMAL_MIN,
            near,
            "styletrace reuse accept",
        )


@dataclass(frozen=True)
class Pools:
    """The pools of the lanes `grid` serves: `mask` (bit q: slot q is a member), their vertices `si`
    and BSDFs; `count`, every lane's children count, and `si_all`, every lane's vertex (default si),
    of the pass; `equal`: every member has v's count (the first round: members share v's style
    slot), so C = |P| c_v without a loop over the slots."""
    grid: Grid
    mask: mi.UInt64
    si: mi.SurfaceInteraction3f
    bsdf: mi.BSDFPtr
    count: mi.UInt32
    si_all: mi.SurfaceInteraction3f | None = None
    equal: bool = True

    @property
    def everyone(self):
        return self.si if self.si_all is None else self.si_all


def _has(mask, q):
    """Whether pool slot q (a UInt32 array) is a member: its bit in the pool's mask."""
    return ((mask >> mi.UInt64(q)) & mi.UInt64(1)) != 0


def _pool_count(grid, mask, count):
    """C = sum over the pool's members of their children counts (count: per lane of the pass)."""
    def body(q, total):
        here = _has(mask, q)
        at, _ = grid.neighbour(q)
        return q + 1, total + dr.select(here, dr.gather(mi.UInt32, count, at, here), 0)
    _, total = dr.while_loop((mi.UInt32(0), mi.UInt32(0)), lambda q, t: q <= grid.K, body,
                             label="styletrace reuse pool count")
    return total


def _total(grid, mask, count, equal):
    """C = sum over the pool's members of their children counts: |P| c_v where all members have
    v's count."""
    if equal:
        return mi.Float(dr.popcnt(mask)) * mi.Float(dr.gather(mi.UInt32, count, grid.lane))
    return mi.Float(_pool_count(grid, mask, count))


def _counts(pools: Pools):
    """(c_v, C, member_count): v's own children count, C = sum over the pool of c_k, and c_k of the
    members at lanes `at` (v's own where all members have it: `equal`)."""
    grid, mask, count, equal = pools.grid, pools.mask, pools.count, pools.equal
    cv = mi.Float(dr.gather(mi.UInt32, count, grid.lane))

    def member_count(at, on):
        return cv if equal else mi.Float(dr.gather(mi.UInt32, count, at, on))
    return cv, _total(grid, mask, count, equal), member_count


def pooled(pools: Pools, slab, J: int, weights: str, moments: bool = False):
    """(direct + indirect)(v) of the module docstring for every lane the grid serves (meaningful
    where the lane pools); member k contributes its first c_k = count_k children, at most J.

    Args:
        pools, slab: the lanes' pools and the children stored per lane (reuse_children.Slab).
        J: the most children a member contributes.
        weights: 'balance', 'pairwise' or 'own' (the tests' negative control).
        moments: also return s1 = sum_i u_i, s2 = sum_i u_i^2 and C = sum_P c_k, u_i = C x_i the
            brightness of child i's terms x_i (they give the pooled mean's sample variance).

    Returns:
        The pooled mean (mi.Spectrum), or (mean, s1, s2, C) with `moments`.
    """
    if weights == "pairwise":
        return _pairwise(pools, slab, J, moments)
    grid, mask, si, bsdf = pools.grid, pools.mask, pools.si, pools.bsdf
    kids, M = slab.kids, slab.M
    ctx = mi.BSDFContext()
    K = grid.K
    si_all = pools.everyone
    active = mask != 0
    cv, C, member_count = _counts(pools)

    def has(q):
        return active & _has(mask, q)

    def mixture(wb, on):
        """sum over pool members q of c_q p_q(wb), p_q at member q's own vertex (v's BSDF object:
        accepted members share it): a loop over the K + 1 slots."""
        def body(q, total):
            here = on & has(q)
            at, _ = grid.neighbour(q)
            sk = dr.gather(mi.SurfaceInteraction3f, si_all, at, here)
            p = bsdf.pdf(ctx, sk, sk.to_local(wb), here)
            total += dr.select(here, member_count(at, here) * p, 0.0)
            return q + 1, total
        _, total = dr.while_loop((mi.UInt32(0), mi.Float(0.0)), lambda q, t: on & (q <= K), body,
                                 label="styletrace reuse densities")
        return total

    def body(i, direct, indirect, s1, s2):
        q, j = i // J, i % J
        at, _ = grid.neighbour(q)
        on = has(q) & (j < member_count(at, has(q)))
        wl, E, wb, pdf, Li, _ = kids.load(at * M + j, on)
        d = dr.select(on, bsdf.eval(ctx, si, si.to_local(wl), on) * E, 0.0)
        take = on & (pdf > 0)
        f = bsdf.eval(ctx, si, si.to_local(wb), take) * Li
        if weights == "balance":    # f Li / sum_P c_k p_k
            w = dr.rcp(mixture(wb, take))
        # 'own': f Li / p_k, averaged over the C samples (wrong: the negative control)
        else:
            w = dr.rcp(pdf * C)
        b = dr.select(take & dr.isfinite(w) & (w > 0), f * w, 0.0)
        direct, indirect = direct + d, indirect + b
        if moments:
            s1, s2 = _moments(s1, s2, on, d + b * C)
        return i + 1, direct, indirect, s1, s2

    _, direct, indirect, s1, s2 = dr.while_loop(
        (mi.UInt32(0), mi.Spectrum(0.0), mi.Spectrum(0.0), mi.Float(0.0), mi.Float(0.0)),
        lambda i, d, ind, a, b: i < (K + 1) * J, body, label="styletrace reuse pool")
    mean = direct / dr.maximum(C, 1.0) + indirect
    return (mean, s1, s2, C) if moments else mean


def _moments(s1, s2, on, y):
    """The running sums of u and u^2, u the brightness (channel mean) of a child's estimate y,
    where `on`."""
    u = channel_mean(y)
    return s1 + dr.select(on, u, 0.0), s2 + dr.select(on, dr.square(u), 0.0)


def _layer(grid, mask, count, j, active):
    """The pool members with more than j children (their slot bits; slot 0, v itself, where c_v
    > j)."""
    def body(q, bits):
        here = active & _has(mask, q)
        at, _ = grid.neighbour(q)
        deep = here & (dr.gather(mi.UInt32, count, at, here) > j)
        return q + 1, bits | dr.select(deep, mi.UInt64(1) << mi.UInt64(q), mi.UInt64(0))
    _, bits = dr.while_loop((mi.UInt32(0), mi.UInt64(0)), lambda q, b: q <= grid.K, body,
                            label="styletrace reuse layer")
    return bits


def _pairwise(pools: Pools, slab, J: int, moments: bool):
    """`pooled` with pairwise weights, n = |P| - 1 (Veach's multi-sample form of each pair):
        a member k's sample:  f_v Li / (n c_k p_k + c_v p_v)
        v's own sample:       f_v Li (1/n) sum_{k != v} 1 / (n c_k p_k + c_v p_v)
    Per child index j, one loop over the members k != v gives both v's terms for k's child j and
    k's term of the canonical sum of v's own child j (v's own f_v Li was stored when drawn).
    Unequal counts (the refinement round): layer j holds the members with c_k > j, pooled with
    pairwise weights over its own members (n_j = |P_j| - 1), the layers averaged with weights
    |P_j| / C. Design: docs/design/sample_reuse.md."""
    grid, mask, si, bsdf, count, equal = (
        pools.grid,
        pools.mask,
        pools.si,
        pools.bsdf,
        pools.count,
        pools.equal,
    )
    kids, M = slab.kids, slab.M
    ctx = mi.BSDFContext()
    K = grid.K
    si_all = pools.everyone
    active = mask != 0
    cv, C, member_count = _counts(pools)

    others = mi.Float(dr.popcnt(mask)) - 1.0                  # n = |P| - 1
    alone = others < 0.5
    own = grid.lane * M

    def index(j, direct, indirect, s1, s2):
        mine = active & (j < cv)
        wl, E, wv, pv, _, fLi = kids.load(own + j, mine)
        if equal:
            n_j, alone_j, scale = others, alone, None
        else:  # layer j: its members, their number less one, and its weight |P_j| / C
            layer = _layer(grid, mask, count, j, active)
            n_j = mi.Float(dr.popcnt(layer)) - 1.0
            alone_j, scale = n_j < 0.5, (n_j + 1.0) / dr.maximum(C, 1.0)
        theirs = mine & (pv > 0) & ~alone_j

        def term(q, here, direct, indirect, s1, s2, canonical):
            at, _ = grid.neighbour(q)
            ck = member_count(at, here)
            on = here & (j < ck)
            wl, E, wb, pdf, Li, _ = kids.load(at * M + j, on)
            d = dr.select(on, bsdf.eval(ctx, si, si.to_local(wl), on) * E, 0.0)
            take = on & (pdf > 0)
            f, p_v = bsdf.eval_pdf(ctx, si, si.to_local(wb), take)
            w = dr.rcp(others * ck * pdf + cv * p_v) if equal else scale * dr.rcp(n_j * pdf + p_v)
            b = dr.select(take & dr.isfinite(w) & (w > 0), f * Li * w, 0.0)
            if moments:
                s1, s2 = _moments(s1, s2, on, d + b * C)
            # v's own child j against member k's technique, at k's vertex
            there = here & theirs
            sk = dr.gather(mi.SurfaceInteraction3f, si_all, at, there)
            p_k = bsdf.pdf(ctx, sk, sk.to_local(wv), there)
            canonical += dr.select(
                there, dr.rcp(others * ck * p_k + cv * pv) if equal else dr.rcp(n_j * p_k + pv), 0.0
            )
            return direct + d, indirect + b, s1, s2, canonical

        if equal:  # every slot q = 1 .. K
            def member(q, *acc):
                here = active & _has(mask, q)
                return q + 1, *term(q, here, *acc)
            _, direct, indirect, s1, s2, canonical = dr.while_loop(
                (mi.UInt32(1), direct, indirect, s1, s2, mi.Float(0.0)),
                lambda q, *_: q <= K,
                member,
                label="styletrace reuse pool members",
            )
        else:      # the layer's members k != v alone: its set bits, lowest first
            def member(bits, *acc):
                q = mi.UInt32(dr.tzcnt(bits))
                return bits & (bits - mi.UInt64(1)), *term(q, bits != 0, *acc)
            _, direct, indirect, s1, s2, canonical = dr.while_loop(
                (layer & ~mi.UInt64(1), direct, indirect, s1, s2, mi.Float(0.0)),
                lambda bits, *_: bits != 0,
                member,
                label="styletrace reuse pool layer",
            )
        d = dr.select(mine, bsdf.eval(ctx, si, si.to_local(wl), mine) * E, 0.0)
        if equal:
            w = dr.select(alone, dr.rcp(cv * pv), canonical / others)
        else:
            w = scale * dr.select(alone_j, dr.rcp(pv), canonical / n_j)
        b = dr.select(mine & (pv > 0) & dr.isfinite(w) & (w > 0), fLi * w, 0.0)
        if moments:
            s1, s2 = _moments(s1, s2, mine, d + b * C)
        return j + 1, direct + d, indirect + b, s1, s2

    zero = (mi.Spectrum(0.0), mi.Spectrum(0.0), mi.Float(0.0), mi.Float(0.0))
    _, direct, indirect, s1, s2 = dr.while_loop((mi.UInt32(0), *zero), lambda j, *_: j < J, index,
                                                label="styletrace reuse pool")
    mean = direct / dr.maximum(C, 1.0) + indirect
    return (mean, s1, s2, C) if moments else mean


def pool_pixels(keep: dict) -> list[list[tuple[int, int]]]:
    """Per lane, the (x, y) pixels of its pool, itself first (tests, docs).

    Args:
        keep: the dict `render_reuse(..., keep=keep)` filled (mask, start, radius, spp, width, K).

    Returns:
        One list of (x, y) per lane of the first batch.
    """
    offsets = window(keep["radius"])
    W, spp, width = len(offsets), keep["spp"], keep["width"]
    out = []
    for lane, (mask, start) in enumerate(zip(keep["mask"], keep["start"])):
        pix = lane // spp
        x, y = pix % width, pix // width
        members = []
        for q in range(keep["K"] + 1):
            if int(mask) >> q & 1:
                dx, dy = (0, 0) if q == 0 else offsets[(int(start) + q - 1) % W]
                members.append((int(x + dx), int(y + dy)))
        out.append(members)
    return out
