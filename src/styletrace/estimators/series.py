"""Power-series estimators: sum_k a_k (I - b)^k with randomly selected, reweighted terms.

Reference: West & Mukherjee, supplement S2.3 (S9-S13), after Georgiev et al. (2019): single
term (S11), iterative prefix sum (S12), recursive Russian roulette (S13); terms "naive" (S6) or
"ustat" (S7-S8). Unbiased when b is independent of the term samples.

`SeriesEstimator(series, b=Pilot(1), selection="iterative", truncation=None, terms=None,
max_terms=64, scaled=False)`. Cost: pilot + the number of terms after the zeroth. Defaults and
rationale: docs/design/power_series.md.
"""
from __future__ import annotations

import numpy as np

from styletrace.estimators import arrays as A
from styletrace.estimators.base import Context, Estimator, check_count
from styletrace.estimators.coefficients import Series
from styletrace.estimators.pilot import ExpansionPoint, Pilot
from styletrace.estimators.polynomial import ustat_update
from styletrace.estimators.truncation import Cumulative, Poisson, PoissonCMF, resolve_truncation

__all__ = ["SeriesEstimator", "SELECTIONS"]

SELECTIONS = ("single", "iterative", "recursive")
MAX_USTAT_TERMS = 64


def _term(coefficient, estimate):
    """a_k * <(I - b)^k>, exactly 0 where the term estimate is 0: a_k itself may overflow to inf in
    float32 (e.g. C(p, k) b^(p - k) for small b and large k), and inf * 0 would turn a zero term
    into NaN."""
    return A.select(estimate == 0, estimate * 0.0, coefficient * estimate)


class SeriesEstimator(Estimator):
    """sum_k a_k (I - b)^k with randomly selected, reweighted terms (the module doc).

    Args:
        series: a `coefficients.Series`, or a fit (its `.series()`).
        b: Pilot(1) if None, a fixed float or per-channel vector, Pilot(n), or PerLane(b).
        selection, terms: one of SELECTIONS; "ustat" (iterative only, its default) or "naive".
        truncation: a `truncation.Truncation` or its name; None: PoissonCMF(2), Cumulative() or
            Poisson(2) for iterative, recursive, single. Adaptive ones: recursive only.
        max_terms: the highest term ever evaluated (ustat: <= 64); scaled: (a_k b^k) ((x-b)/b)^k.

    Raises:
        ValueError: a bad series, selection, truncation, terms, max_terms or combination of them.
    """

    def __init__(self, series, b=None, selection: str = "iterative", truncation=None, terms=None,
                 max_terms: int = 64, scaled: bool = False):
        if not isinstance(series, Series):
            if hasattr(series, "series") and callable(series.series):
                series = series.series()
            else:
                raise ValueError(f"series must be a coefficients.Series (or a fit), got {series!r}")
        self.series = series
        if selection not in SELECTIONS:
            raise ValueError(f"unknown selection {selection!r}; allowed: {', '.join(SELECTIONS)}")
        self.selection = selection
        if truncation is None:
            truncation = {"iterative": PoissonCMF(2.0), "recursive": Cumulative(),
                          "single": Poisson(2.0)}[selection]
        self.truncation = resolve_truncation(truncation)
        if terms is None:
            terms = "ustat" if selection == "iterative" else "naive"
        if terms not in ("naive", "ustat"):
            raise ValueError(f"unknown term estimator {terms!r}; allowed: 'naive', 'ustat'")
        if terms == "ustat" and selection != "iterative":
            raise ValueError(
                f"terms='ustat' needs the number of terms before the samples are drawn: use "
                f"selection='iterative' (got selection={selection!r})"
            )
        self.terms = terms
        self.scaled = bool(scaled)
        if self.scaled and not (selection == "iterative" and terms == "ustat"
                                and hasattr(series, "ratio")):
            raise ValueError(
                "scaled=True needs selection='iterative', terms='ustat' and a series defined by "
                f"its coefficient ratio (got {selection!r}, {terms!r}, {series.name})"
            )
        if self.truncation.adaptive and selection != "recursive":
            raise ValueError(f"{self.truncation.name} truncation adapts to the samples, so only "
                             f"selection='recursive' can use it (got {selection!r})")
        self.max_terms = check_count("max_terms", max_terms, 1)
        self.point = ExpansionPoint(Pilot(1) if b is None else b, series=series)

        limit = self.max_terms if series.degree is None else min(self.max_terms, series.degree)
        if self.truncation.adaptive:
            self.K = limit
        else:
            self.K, self.S, self.invS, self.q, self.pmf = self.truncation.tables(limit)
            if selection == "single":
                bad = np.flatnonzero(self.pmf <= 0.0)
                if bad.size:
                    raise ValueError(
                        f"single-term selection needs P(k) > 0 for every term k <= {self.K}, but "
                        f"{self.truncation.name} gives P(k) = 0 for k in {bad.tolist()}; use "
                        f"Poisson(tau) or Geometric(p)"
                    )
                self.inv_pmf = 1.0 / self.pmf
        if terms == "ustat" and self.K > MAX_USTAT_TERMS:
            raise ValueError(
                f"terms='ustat' keeps one running mean per term; K={self.K} > {MAX_USTAT_TERMS}: "
                f"lower max_terms"
            )
        self.name = (f"series[{series.name}; {selection}/{self.truncation.name}/{terms}; "
                     f"{self.point.describe()}]")

    # -- helpers ----------------------------------------------------------------------------------
    def _b(self, ctx, state):
        return self.point.value(ctx, state)

    def _cs_start(self, ctx, state=None):
        if self.point.lane:
            return tuple(self.series.start(ctx, state["b"]))
        if self.point.pilot:
            if state is None:
                return tuple(ctx.vzero() for _ in range(self.series.state_len))
            return tuple(self.series.start(ctx, state["b"]))
        return tuple(self.series.start_fixed(ctx, self.point.fixed))

    def exact(self, I):
        return self.series.function(I)

    # -- protocol -------------------------------------------------------------------------------
    def start(self, ctx: Context, carry):
        state = self.point.start(ctx)
        state["cs"] = self._cs_start(ctx, state if self.point.lane else None)
        state["k"] = ctx.lane(0.0)
        state["prod"] = ctx.value_array(1.0)
        sel = self.selection
        if sel in ("recursive", "iterative") and self.terms == "naive":
            state["acc"] = ctx.vzero() + self.series.coefficient(state["cs"])
        if sel == "recursive":
            u, carry = ctx.uniform(carry)
            q1 = 1.0 if self.truncation.adaptive else float(self.q[1])
            alive = (u < q1) & ctx.mask(self.K >= 1)
            state["alive"] = alive
            state["Q"] = A.select(alive, ctx.lane(q1), ctx.lane(1.0))
            if self.truncation.adaptive:
                state["scale"] = self._scale(ctx, state["acc"])
        else:
            u, carry = ctx.uniform(carry)
            state["N"] = ctx.count_above(self.S, u)
            if sel == "single":
                state["w"] = ctx.lookup(self.inv_pmf, state["N"])
            elif self.terms == "ustat":
                state["m"] = tuple(ctx.vzero() for _ in range(self.K))
        return state, carry

    def _scale(self, ctx, a0):
        s = A.abs(a0)
        return A.select(s > 0.0, s, s * 0.0 + 1.0)

    def wants(self, ctx, state):
        w = state["alive"] if self.selection == "recursive" else state["k"] < state["N"]
        inp = self.point.in_pilot(state)
        return w if inp is None else (w | inp)

    def feed(self, ctx, state, x, mask, carry):
        inp = self.point.in_pilot(state)
        if inp is not None:
            state, done = self.point.feed(ctx, state, x, mask)
            state["cs"] = ctx.when(done, lambda: self._cs_start(ctx, state), state["cs"])
            if "acc" in state:
                a0 = ctx.vzero() + self.series.coefficient(state["cs"])
                state["acc"] = A.select(done, a0, state["acc"])
                if "scale" in state:
                    state["scale"] = A.select(done, self._scale(ctx, a0), state["scale"])
            mask = mask & ~inp
        else:
            state = dict(state)
        b = self._b(ctx, state)
        y = (x - b) / b if self.scaled else x - b
        k = state["k"]
        k1 = k + 1.0
        new = {"k": k1}
        if self.selection == "iterative" and self.terms == "ustat":
            m = ustat_update(list(state["m"]), y, k1)
            new["m"] = tuple(m)
        else:
            prod = state["prod"] * y
            cs = tuple(self.series.advance(ctx, state["cs"], k, b))
            new["prod"], new["cs"] = prod, cs
            if self.selection != "single":
                term = _term(self.series.coefficient(cs), prod)
                if self.selection == "iterative":
                    new["acc"] = state["acc"] + term * ctx.lookup(self.invS, k1)
                else:
                    Q = state["Q"]
                    new["acc"] = state["acc"] + term * (1.0 / Q)
                    if self.truncation.adaptive:
                        W = A.hmax(A.abs(term) / (state["scale"] * Q))
                        q = A.clip(W, self.truncation.min_continue, 1.0)
                    else:
                        q = ctx.lookup(self.q, k1 + 1.0)
                    u, carry = ctx.uniform(carry)
                    alive = (u < q) & (k1 < float(self.K))
                    new["alive"] = alive
                    new["Q"] = A.select(alive, Q * q, Q)
        for key, v in new.items():
            if isinstance(v, tuple):
                state[key] = tuple(A.select(mask, a, o) for a, o in zip(v, state[key]))
            else:
                state[key] = A.select(mask, v, state[key])
        return state, carry

    def value(self, ctx, state):
        if self.selection == "single":
            return _term(self.series.coefficient(state["cs"]), state["prod"]) * state["w"]
        if self.terms == "naive":
            return state["acc"]
        b = self._b(ctx, state)
        cs = self._cs_start(ctx, state)
        out = ctx.vzero() + self.series.coefficient(cs)
        advance = self.series.advance_scaled if self.scaled else self.series.advance
        for k in range(1, self.K + 1):
            cs = advance(ctx, cs, ctx.lane(float(k - 1)), b)
            out = out + _term(self.series.coefficient(cs), state["m"][k - 1]) * float(self.invS[k])
        return out

    @property
    def mean_draws(self):
        if self.truncation.adaptive:
            return None
        if self.selection == "single":
            terms = float(np.dot(np.arange(len(self.pmf)), self.pmf))
        else:
            terms = float(np.sum(self.S[1:]))
        return self.point.draws + terms
