"""Affine style functions and the (optionally comb-stratified) sample mean.

Reference: West & Mukherjee, supplement Eqs. S1-S3: g(I) = a1 I + a0, <g(I)> = a1 <I> + a0, unbiased
for any unbiased <I>, here the mean of n draws. `Mean(m)` is the building block of multi-sample
inner estimates (Kettunen, d'Eon, Pantaleoni, Novak 2021; `algebra.inner_mean`).

`Affine(a1, a0=0, n=1, comb=False)`: a1 a scalar, one value per channel or a (C, C) matrix; a0 a
scalar or one value per channel; n >= 1 draws per estimate; comb stratifies them with one random
offset per estimate (docs/design/comb_stratification.md). `Mean(m, comb=False)` is Affine(1, 0, m,
comb).
"""
from __future__ import annotations

import numpy as np

from styletrace.estimators import arrays as A
from styletrace.estimators.base import Context, Estimator, check_count

__all__ = ["Affine", "Mean", "MeanOfN", "apply_linear"]


def apply_linear(a1: np.ndarray, x):
    """a1 x for a scalar, per-channel vector or (C, C) matrix a1.

    Args:
        a1: a float64 array: 0-D, (C,) per channel, or (C, C) (y = A x, mixing channels).
        x: numpy (..., C), or a Dr.Jit value (a C-channel one for a matrix).

    Returns:
        a1 x, of x's kind.

    Raises:
        ValueError: a matrix whose size is not x's channel count (per-channel: `const_like`'s).
    """
    if a1.ndim < 2:
        return A.const_like(a1, x) * x if a1.ndim == 1 else float(a1) * x
    C = a1.shape[0]
    if A.is_drjit(x):
        dr = A.drjit()
        if dr.depth_v(x) < 2 or len(x) != C:
            raise ValueError(f"a ({C}, {C}) matrix needs {C}-channel values, got "
                             f"{type(x).__name__}")
        return type(x)(*[sum(float(a1[i, j]) * x[j] for j in range(C)) for i in range(C)])
    x = np.asarray(x)
    if x.shape[-1] != C:
        raise ValueError(f"a ({C}, {C}) matrix needs values with {C} channels, got shape {x.shape}")
    return x @ a1.T


class MeanOfN(Estimator):
    """The running mean of n draws (optionally comb-stratified) that Affine and Direct both finish
    from.

    Args:
        n: draws per estimate (>= 1); comb: stratify them (docs/design/comb_stratification.md).
        cap: (k >= 1, floor >= 0), the firefly control, or None. The brightest draw (by channel
            mean) is scaled down to at most k * max(mean brightness of the other n - 1, floor); a
            lone draw to at most LONE_CAP * floor (none if floor is 0). Biased (it lowers rare
            bright draws); docs/look.md says by how much.

    Raises:
        ValueError: n not an integer >= 1, or a bad cap.
    """

    #: a lone draw's cap in units of `floor` (the scene's median brightness): Cycles' indirect clamp
    #: of 10 at the exposure that maps the median to middle grey (10 / 0.18)
    LONE_CAP = 10.0 / 0.18

    def __init__(self, n: int, comb: bool = False, cap: tuple[float, float] | None = None):
        self.n = check_count("n", n)
        self.comb = bool(comb)
        if cap is not None and not (cap[0] >= 1.0 and cap[1] >= 0.0):
            raise ValueError(f"cap must be (k >= 1, floor >= 0), got {cap!r}")
        self.cap = (None if cap is None or (self.n == 1 and cap[1] <= 0.0)
                    else (float(cap[0]), float(cap[1])))

    def start(self, ctx: Context, carry):
        state = {"sum": ctx.vzero(), "count": ctx.lane(0.0)}
        if self.cap is not None:
            state["top"], state["top_b"] = ctx.vzero(), ctx.lane(-1.0)
        if self.comb:
            state["offset"], carry = ctx.uniform(carry)
        return state, carry

    def wants(self, ctx, state):
        return state["count"] < self.n

    def next_u(self, ctx, state):
        if not self.comb:
            return None
        return (state["offset"] + state["count"]) * (1.0 / self.n)

    def feed(self, ctx, state, x, mask, carry):
        state = dict(state)
        state["sum"] = A.select(mask, state["sum"] + x, state["sum"])
        state["count"] = A.select(mask, state["count"] + 1.0, state["count"])
        if self.cap is not None:
            b = A.channel_mean(x)
            brighter = mask & (b > state["top_b"])
            state["top"] = A.select(brighter, x, state["top"])
            state["top_b"] = A.select(brighter, b, state["top_b"])
        return state, carry

    def mean(self, state):
        """The mean of the n draws, the brightest one capped where `cap` says.

        Args:
            state: the loop state after n draws.

        Returns:
            The per-lane mean value (like x).
        """
        total = state["sum"]
        if self.cap is not None:
            k, floor = self.cap
            top, top_b = state["top"], state["top_b"]
            # the floor (the scene's median brightness, pinned per render) as a kernel input: an
            # edit that moves it reuses the compiled kernel
            floor = A.input_like(floor, top_b)
            if self.n == 1:
                limit = self.LONE_CAP * floor
            else:
                others = A.channel_mean(total - top) * (1.0 / (self.n - 1))
                limit = k * A.maximum(others, floor)
            over = top_b > limit
            scale = A.select(over, limit / A.select(over, top_b, 1.0), 1.0)
            total = total - top + top * scale
        return total * (1.0 / self.n)

    @property
    def mean_draws(self):
        return float(self.n)

    @property
    def fixed_draws(self):
        return True

    @property
    def uses_comb(self):
        return self.comb


class Affine(MeanOfN):
    """a1 <I>_n + a0: unbiased for an affine g (supplement Eqs. S1-S3).

    Args:
        a1: a scalar, one value per channel (C,), or a (C, C) matrix (y = A x, mixing channels).
        a0: a scalar or one value per channel.
        n: draws averaged per estimate (>= 1); comb: stratify them with the comb.

    Raises:
        ValueError: a1 or a0 of a bad shape or not finite; n not an integer >= 1.
    """

    def __init__(self, a1=1.0, a0=0.0, n: int = 1, comb: bool = False):
        self.a1 = np.asarray(a1, dtype=np.float64)
        self.a0 = np.asarray(a0, dtype=np.float64)
        if self.a1.ndim > 2 or (self.a1.ndim == 2 and self.a1.shape[0] != self.a1.shape[1]):
            raise ValueError("a1 must be a scalar, a per-channel vector or a square matrix, got "
                             f"shape {self.a1.shape}")
        if self.a0.ndim > 1:
            raise ValueError("a0 must be a scalar or a per-channel vector, got shape "
                             f"{self.a0.shape}")
        if not (np.all(np.isfinite(self.a1)) and np.all(np.isfinite(self.a0))):
            raise ValueError(f"a1 and a0 must be finite, got a1={a1!r}, a0={a0!r}")
        super().__init__(n, comb)
        self.name = f"affine(n={self.n}{', comb' if comb else ''})"

    def value(self, ctx, state):
        return apply_linear(self.a1, self.mean(state)) + ctx.vconst(self.a0)

    def exact(self, I):
        I = np.asarray(I, dtype=np.float64) if not A.is_drjit(I) else I
        y = apply_linear(self.a1, I)
        return y + (A.const_like(self.a0, y) if self.a0.ndim else float(self.a0))


def Mean(m: int = 1, comb: bool = False) -> Affine:
    """The mean of m draws (optionally comb-stratified): a gu estimator of I itself.

    Args:
        m: draws per estimate (>= 1); comb: stratify them with the comb.

    Returns:
        Affine(1, 0, m, comb), named "mean(m=...)".

    Raises:
        ValueError: m not an integer >= 1.
    """
    est = Affine(1.0, 0.0, n=m, comb=comb)
    est.name = f"mean(m={est.n}{', comb' if comb else ''})"
    return est
