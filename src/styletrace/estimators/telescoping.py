"""Telescoping debiasing of the direct estimator (randomized telescoping sum).

Reference: West & Mukherjee, Eq. 15 (form inferred), after Misso, Li, Burley, Teece, Jarosz,
"Unbiased and Consistent Rendering using Biased Estimators" (2022):
    <g(I)> = g(<I>_n0) + sum_{j=1..N} [g(<I>_(n0+j)) - g(<I>_(n0+j-1))] / P(N >= j),
N drawn before the samples; the nested means share samples, so N differences cost N draws. Its
expectation is the direct estimator's at n0 + K samples, K the largest reachable term: unbiased only
as K -> infinity. Heavy tails (PowerLaw) keep the variance finite; light tails make 1/P explode.

`Telescoping(g, n0=1, truncation=PowerLaw(1.5), max_terms=2**16)`. Details:
docs/design/power_series.md.
"""
from __future__ import annotations

import numpy as np

from styletrace.estimators import arrays as A
from styletrace.estimators.base import Context, Estimator, check_count
from styletrace.estimators.truncation import PowerLaw, resolve_truncation

__all__ = ["Telescoping"]


class Telescoping(Estimator):
    """The randomized telescoping sum of the module doc, N drawn before the samples.

    Args:
        g: callable g(x) -> y, array-generic.
        n0: samples of the base term (>= 1).
        truncation: a sample-independent `truncation.Truncation` or its name; None: PowerLaw(1.5).
        max_terms: the most differences N (>= 1).

    Raises:
        ValueError: g not callable, a bad count, or an adaptive or unknown truncation.
    """

    def __init__(self, g, n0: int = 1, truncation=None, max_terms: int = 1 << 16):
        if not callable(g):
            raise ValueError(f"g must be a callable g(x) -> y, got {g!r}")
        self.g = g
        self.n0 = check_count("n0", n0)
        self.truncation = resolve_truncation(PowerLaw(1.5) if truncation is None else truncation)
        if self.truncation.adaptive:
            raise ValueError("telescoping needs N drawn before the samples; "
                             f"{self.truncation.name} adapts to them")
        self.max_terms = check_count("max_terms", max_terms)
        self.K, self.S, self.invS, _, _ = self.truncation.tables(self.max_terms)
        self.name = f"telescoping(n0={self.n0}, {self.truncation.name}, K={self.K})"

    def start(self, ctx: Context, carry):
        u, carry = ctx.uniform(carry)
        state = {"sum": ctx.vzero(), "count": ctx.lane(0.0), "N": ctx.count_above(self.S, u),
                 "acc": ctx.vzero(), "prev": ctx.vzero()}
        return state, carry

    def wants(self, ctx, state):
        return state["count"] < self.n0 + state["N"]

    def feed(self, ctx, state, x, mask, carry):
        state = dict(state)
        s = state["sum"] + x
        c = state["count"] + 1.0
        gv = ctx.vzero() + self.g(s * (1.0 / c))
        j = c - float(self.n0)
        diff = (gv - state["prev"]) * ctx.lookup(self.invS, j)
        acc = A.select(j > 0.0, state["acc"] + diff, A.select(j == 0.0, gv, state["acc"]))
        state["acc"] = A.select(mask, acc, state["acc"])
        state["prev"] = A.select(mask, gv, state["prev"])
        state["sum"] = A.select(mask, s, state["sum"])
        state["count"] = A.select(mask, c, state["count"])
        return state, carry

    def value(self, ctx, state):
        return state["acc"]

    def exact(self, I):
        return self.g(I)

    @property
    def mean_draws(self):
        return float(self.n0 + np.sum(self.S[1:]))
