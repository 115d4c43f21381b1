"""Direct application: g applied to the mean of n samples (biased, consistent).

Reference
    West & Mukherjee, "Stylized Rendering as a Function of Expectation", Eq. 19:
        <g(I)>_direct = g(<I>_n),   <I>_n = (1/n) sum_i x_i.
    Its bias is, to first order (delta method, Eq. 21), tr(H_g Cov[x]) / (2n), i.e. g''(I) Var[x] /
    (2n) per channel; it vanishes as 1/n, so the estimator is consistent but never group-unbiased.

Parameters
    g      callable, array-generic: g(x) -> y with x a value (numpy (lanes, C) or a Dr.Jit array).
    n      samples per estimate (>= 1).
    comb   False (default): n independent draws. True: a stratified discrete comb, the i-th draw
    gets
           first primary dimension (xi + i)/n with one uniform xi per estimate (see
           ``affine.Mean``).
    cap    None (default), or (k, floor): the firefly control of ``affine.MeanOfN`` on the mean
    (biased).
"""
from __future__ import annotations

from .affine import MeanOfN

__all__ = ["Direct"]


class Direct(MeanOfN):
    def __init__(self, g, n: int, comb: bool = False, cap: tuple[float, float] | None = None):
        if not callable(g):
            raise ValueError(f"g must be a callable g(x) -> y, got {g!r}")
        super().__init__(n, comb, cap)
        self.g = g
        self.name = f"direct(n={self.n}{', comb' if comb else ''}{', capped' if self.cap else ''})"

    def value(self, ctx, state):
        return self.g(self.mean(state))

    def exact(self, I):
        return self.g(I)
