"""Direct application: g applied to the mean of n samples (biased, consistent).

Reference
    West & Mukherjee, "Stylized Rendering as a Function of Expectation", Eq. 19:
        <g(I)>_direct = g(<I>_n),   <I>_n = (1/n) sum_i x_i.
    Its bias is, to first order (delta method, Eq. 21), tr(H_g Cov[x]) / (2n), i.e. g''(I) Var[x] / (2n)
    per channel; it vanishes as 1/n, so the estimator is consistent but never group-unbiased.

Parameters
    g      callable, array-generic: g(x) -> y with x a value (numpy (lanes, C) or a Dr.Jit array).
    n      samples per estimate (>= 1).
    comb   False (default): n independent draws. True: a stratified discrete comb, the i-th draw gets
           first primary dimension (xi + i)/n with one uniform xi per estimate (see ``affine.Mean``).
"""
from __future__ import annotations

from . import arrays as A
from .base import Context, Estimator, check_count

__all__ = ["Direct"]


class Direct(Estimator):
    def __init__(self, g, n: int, comb: bool = False):
        if not callable(g):
            raise ValueError(f"g must be a callable g(x) -> y, got {g!r}")
        self.g = g
        self.n = check_count("n", n)
        self.comb = bool(comb)
        self.name = f"direct(n={self.n}{', comb' if comb else ''})"

    def start(self, ctx: Context, carry):
        state = {"sum": ctx.vzero(), "count": ctx.lane(0.0)}
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
        return state, carry

    def value(self, ctx, state):
        return self.g(state["sum"] * (1.0 / self.n))

    def exact(self, I):
        return self.g(I)

    @property
    def mean_samples(self):
        return float(self.n)

    @property
    def fixed_samples(self):
        return True

    @property
    def uses_comb(self):
        return self.comb
