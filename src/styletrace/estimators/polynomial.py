"""Unbiased estimators of polynomials of I: naive products (S6) and the U-statistic (S7-S8).

Reference: West & Mukherjee, supplement S2.2 (Lee, Tiberi, Zanella 2019; Halmos 1946):
    naive        <I^k> = x_1 ... x_k                      (S6)
    U-statistic  <I^k> = e_k(x_1..x_n) / C(n, k)          (S7-S8)
computed with Kettunen, d'Eon, Pantaleoni, Novak's running-mean recurrence (2021, Algorithm 1), m_k
+= (k / n) (x_n m_(k-1) - m_k): no binomials, no overflow, all terms in one pass.

`PolynomialNaive(poly, b=None)`: poly a PolynomialSeries, a fit or coefficients of I^k; b None (the
polynomial's centre), a fixed value or Pilot(n); cost: degree K samples (terms share their prefix).
`PolynomialU(poly, n, b=None)`: n >= K samples (plus the pilot).
"""
from __future__ import annotations

from styletrace.estimators import arrays as A
from styletrace.estimators.base import Context, Estimator, check_count
from styletrace.estimators.coefficients import PolynomialSeries
from styletrace.estimators.pilot import ExpansionPoint

__all__ = ["ustat_update", "u_statistic_means", "PolynomialNaive", "PolynomialU", "as_polynomial"]


def ustat_update(m: list, y, j) -> list:
    """One step of the running-mean recurrence: m = [m_1..m_K] after j-1 samples -> after j.

    Args:
        m: [m_1..m_K] after j - 1 samples (m_0 = 1 is implied).
        y: the j-th sample (of x - b), numpy or Dr.Jit.
        j: the sample's 1-based index, a Python int or a per-lane array.

    Returns:
        A new list [m_1..m_K] after j samples; terms with k > j stay exactly 0 (their inputs are).
    """
    inv_j = 1.0 / j
    out = list(m)
    for k in range(len(out), 0, -1):
        prev = out[k - 2] if k >= 2 else 1.0
        out[k - 1] = out[k - 1] + (k * inv_j) * (y * prev - out[k - 1])
    return out


def u_statistic_means(samples, K: int) -> list:
    """[m_0, ..., m_K] for samples[0..n-1] (axis 0), with m_k = e_k / C(n, k), in the samples'
    precision.

    Args:
        samples: n samples along axis 0 (a sequence or numpy array).
        K: the highest order (an integer >= 0, at most n).

    Returns:
        K + 1 arrays (m_0 = 1).

    Raises:
        ValueError: K not an integer >= 0, or fewer than K samples.
    """
    K = check_count("K", K, 0)
    n = len(samples)
    if n < K:
        raise ValueError(f"a U-statistic of order K={K} needs at least K samples, got n={n}")
    zero = samples[0] * 0.0
    m = [zero for _ in range(K)]
    for j in range(1, n + 1):
        m = ustat_update(m, samples[j - 1], j)
    return [zero + 1.0] + m


def as_polynomial(poly) -> PolynomialSeries:
    """A polynomial given in any accepted form, as a PolynomialSeries.

    Args:
        poly: a PolynomialSeries, anything with a `series()` (a fit), or coefficients of I^k.

    Returns:
        The PolynomialSeries (coefficients: about 0).

    Raises:
        ValueError: coefficients the PolynomialSeries refuses.
    """
    if isinstance(poly, PolynomialSeries):
        return poly
    if hasattr(poly, "series") and callable(poly.series):
        return poly.series()
    return PolynomialSeries(poly, 0.0)


class _PolynomialBase(Estimator):
    def __init__(self, poly, b):
        self.poly = as_polynomial(poly)
        self.point = ExpansionPoint(b, default=self.poly.center)
        self.K = self.poly.degree
        if not self.point.pilot:
            self.fixed_coeffs = self.poly.shifted(self.point.fixed).coeffs

    def exact(self, I):
        return self.poly.function(I)

    def _y(self, ctx, state, x):
        return x - self.point.value(ctx, state)

    def _feed_pilot(self, ctx, state, x, mask):
        """Give x to the pilot on lanes still collecting it; returns (state copy, lanes for the
        terms)."""
        inp = self.point.in_pilot(state)
        if inp is None:
            return dict(state), mask
        state, _ = self.point.feed(ctx, state, x, mask)
        return state, mask & ~inp

    def _combine(self, ctx, state, terms):
        """sum_k a_k term_k, the term estimates of (x - b)^k for k = 1..K."""
        coef = self._coefficients(ctx, state)
        out = ctx.vzero() + coef[0]
        for k in range(1, self.K + 1):
            out = out + coef[k] * terms[k - 1]
        return out

    def _coefficients(self, ctx, state):
        """a_0..a_K about b: host constants for a fixed b, re-expanded per lane for a pilot b."""
        if self.point.pilot:
            return self.poly.start(ctx, state["b"])
        return [ctx.vconst(c) for c in self.fixed_coeffs]


class PolynomialNaive(_PolynomialBase):
    """Unbiased sum_k a_k (I - b)^k from products of independent samples (S6); K draws (the terms
    share their prefix), plus the pilot's.

    Args:
        poly: a PolynomialSeries, a fit, or coefficients of I^k.
        b: None (the polynomial's center), a fixed value or per-channel vector, or Pilot(n).

    Raises:
        ValueError: a bad polynomial or expansion point.
    """

    def __init__(self, poly, b=None):
        super().__init__(poly, b)
        self.name = f"poly-naive(K={self.K}, {self.point.describe()})"

    def start(self, ctx: Context, carry):
        state = self.point.start(ctx)
        # P[k-1] = product of the first k samples of (x - b); coefficients are applied at the end,
        # so a pilot b costs one re-expansion per estimate, not one per sample
        state["P"] = tuple(ctx.vzero() for _ in range(self.K))
        state["prod"] = ctx.value_array(1.0)
        state["k"] = ctx.lane(0.0)
        return state, carry

    def wants(self, ctx, state):
        w = state["k"] < self.K
        inp = self.point.in_pilot(state)
        return w if inp is None else (w | inp)

    def feed(self, ctx, state, x, mask, carry):
        state, mask = self._feed_pilot(ctx, state, x, mask)
        prod = state["prod"] * self._y(ctx, state, x)
        k = state["k"] + 1.0
        state["P"] = tuple(A.select(mask & (k == float(j + 1)), prod, P)
                           for j, P in enumerate(state["P"]))
        state["prod"] = A.select(mask, prod, state["prod"])
        state["k"] = A.select(mask, k, state["k"])
        return state, carry

    def value(self, ctx, state):
        return self._combine(ctx, state, state["P"])

    @property
    def mean_draws(self):
        return float(self.point.draws + self.K)

    @property
    def fixed_draws(self):
        return True


class PolynomialU(_PolynomialBase):
    """Unbiased sum_k a_k (I - b)^k from the U-statistics of n samples (S7-S8), plus the pilot's.

    Args:
        poly: a PolynomialSeries, a fit, or coefficients of I^k.
        n: samples per estimate, at least the degree K.
        b: None (the polynomial's center), a fixed value or per-channel vector, or Pilot(m).

    Raises:
        ValueError: a bad polynomial or expansion point, or n not an integer >= K.
    """

    def __init__(self, poly, n: int, b=None):
        super().__init__(poly, b)
        self.n = check_count("n", n)
        if self.n < self.K:
            raise ValueError(f"the U-statistic of a degree-{self.K} polynomial needs n >= {self.K} "
                             f"samples, got n={self.n}")
        self.name = f"poly-U(K={self.K}, n={self.n}, {self.point.describe()})"

    def start(self, ctx: Context, carry):
        state = self.point.start(ctx)
        state["m"] = tuple(ctx.vzero() for _ in range(self.K))
        state["j"] = ctx.lane(0.0)
        return state, carry

    def wants(self, ctx, state):
        w = state["j"] < self.n
        inp = self.point.in_pilot(state)
        return w if inp is None else (w | inp)

    def feed(self, ctx, state, x, mask, carry):
        state, mask = self._feed_pilot(ctx, state, x, mask)
        j = state["j"] + 1.0
        m = ustat_update(list(state["m"]), self._y(ctx, state, x), A.maximum(j, 1.0))
        state["m"] = tuple(A.select(mask, new, old) for new, old in zip(m, state["m"]))
        state["j"] = A.select(mask, j, state["j"])
        return state, carry

    def value(self, ctx, state):
        return self._combine(ctx, state, state["m"])

    @property
    def mean_draws(self):
        return float(self.point.draws + self.n)

    @property
    def fixed_draws(self):
        return True
