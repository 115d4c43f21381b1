"""Coefficient generators: g(I) = sum_k a_k(b) (I - b)^k about a (possibly per-lane) point b.

Reference: West & Mukherjee, "Stylized Rendering as a Function of Expectation", supplement S2.3-S2.6
and Eq. 24: exp (S15, any b), reciprocal a/I (S17, |b - I| < |b|), power I^p (Eq. 24, b > 0), Taylor
from a derivative (S10, S25), and a finite polynomial re-expanded about b (S18).

A `Series` offers `start`, `start_fixed`, `coefficient`, `advance`, `advance_scaled` (a_k b^k),
`coefficients(b, K)` (host float64), `function(I)`, `check_center(b)` (ValueError when a fixed b is
outside the convergence region, given the known range of I) and `clamp_center(b)` (a pilot b moved
into it). Convergence checks in full and rationale: docs/design/power_series.md.
"""
from __future__ import annotations

import math

import numpy as np

from styletrace.estimators import arrays as A

__all__ = [
    "Series",
    "PolynomialSeries",
    "ExpSeries",
    "ReciprocalSeries",
    "PowerFunctionSeries",
    "TaylorSeries",
    "exp_series",
    "reciprocal_series",
    "power_series",
    "gamma_series",
    "taylor_series",
    "polynomial_series",
    "taylor_shift",
]

#: Pilot expansion points are clamped to at least this fraction of the range's far end.
PILOT_FRACTION = 0.55
TINY = 1e-6


def taylor_shift(coeffs: list, h) -> list:
    """Coefficients of p about b from those about c, h = b - c (array-generic, O(K^2)).

    Args:
        coeffs: c_0..c_K of p about c (numbers, numpy or Dr.Jit arrays).
        h: the shift b - c (a number or per-lane array).

    Returns:
        A new list of the K + 1 coefficients about b.
    """
    c = list(coeffs)
    K = len(c) - 1
    for i in range(K):
        for j in range(K - 1, i - 1, -1):
            c[j] = c[j] + h * c[j + 1]
    return c


def _finite_real(name, v):
    if (isinstance(v, bool) or not isinstance(v, (int, float, np.floating, np.integer))
            or not math.isfinite(v)):
        raise ValueError(f"{name} must be a finite real number, got {v!r}")
    return float(v)


def _check_range(lo, hi):
    if (lo is None) != (hi is None):
        raise ValueError(f"give both lo and hi of the known range of I, or neither (got lo={lo!r}, "
                         f"hi={hi!r})")
    if lo is None:
        return None, None
    lo, hi = _finite_real("lo", lo), _finite_real("hi", hi)
    if not lo <= hi:
        raise ValueError(f"the range of I needs lo <= hi, got lo={lo}, hi={hi}")
    return lo, hi


class Series:
    """A coefficient generator (the module doc; used by `series.SeriesEstimator` and `polynomial`).

    Coefficient states are tuples of `state_len` per-lane arrays; `degree` is None for an infinite
    series; `channels` the channel count of per-channel coefficients (None: scalar).
    """

    degree = None  # None: infinite
    channels = None
    name = "series"
    state_len = 1  # arrays in the coefficient state

    def function(self, I):
        """The exact g(I).

        Args:
            I: numpy or Dr.Jit values.

        Returns:
            g(I), of I's kind.
        """
        raise NotImplementedError

    def check_center(self, b):
        """Refuse a fixed expansion point outside the convergence region (default: any b is fine).

        Args:
            b: the fixed point (a float or per-channel vector).

        Raises:
            ValueError: b is outside the region, given the known range of I.
        """

    def clamp_center(self, b):
        """A pilot's expansion point moved into the convergence region (default: b as it is).

        Args:
            b: per-lane expansion points (array-generic).

        Returns:
            The clamped points.
        """
        return b

    def start(self, ctx, b) -> tuple:
        """The coefficient state at k = 0 for a per-lane b.

        Args:
            ctx: the run's `base.Context`; b: per-lane expansion points (a value array).

        Returns:
            The state, a tuple of `state_len` per-lane arrays.
        """
        raise NotImplementedError

    def start_fixed(self, ctx, b) -> tuple:
        """The coefficient state at k = 0 for a fixed b.

        Args:
            ctx: the run's `base.Context`; b: a host float or per-channel vector.

        Returns:
            The state, as `start`'s.
        """
        return self.start(ctx, ctx.value_array(b))

    def coefficient(self, state):
        """a_k of a coefficient state.

        Args:
            state: the state at k.

        Returns:
            a_k, a per-lane value.
        """
        return state[0]

    def advance(self, ctx, state, k, b) -> tuple:
        """The coefficient state at k + 1.

        Args:
            ctx: the run's `base.Context`; state: the state at k.
            k: the current index (a per-lane float); b: the expansion points the state was made for.

        Returns:
            The state at k + 1.
        """
        raise NotImplementedError

    def advance_scaled(self, ctx, state, k, b) -> tuple:
        """`advance` for the scaled coefficients a_k b^k (ratio series only): the terms are
        (a_k b^k) ((I - b) / b)^k, whose factors stay within float32 where a_k alone overflows.

        Args:
            ctx, state, k, b: as `advance`'s (the state holds a_k b^k).

        Returns:
            The state at k + 1.

        Raises:
            ValueError: a series not defined by its coefficient ratio.
        """
        raise ValueError(f"{self.name}: scaled terms need a series defined by its coefficient "
                         "ratio")

    def coefficients(self, b, K: int) -> np.ndarray:
        """a_0..a_K for a fixed b, host float64 (tests, docs).

        Args:
            b: a float or per-channel vector.
            K: the last index (a finite series may take None: its own degree).

        Returns:
            Shape (K+1,) or (K+1, C).
        """
        raise NotImplementedError


# ---------------------------------------------------------------------------------------------
# infinite series defined by a_0(b) and the ratio a_(k+1) / a_k


class _RatioSeries(Series):
    def a0(self, b):
        raise NotImplementedError

    def ratio(self, k, b):
        raise NotImplementedError

    def start(self, ctx, b):
        return (self.a0(b),)

    def advance(self, ctx, state, k, b):
        return (state[0] * self.ratio(k, b),)

    def advance_scaled(self, ctx, state, k, b):
        return (state[0] * (self.ratio(k, b) * b),)

    def coefficients(self, b, K):
        b = np.asarray(b, dtype=np.float64)
        out = [self.a0(b)]
        for k in range(K):
            out.append(out[-1] * self.ratio(float(k), b))
        return np.array(out, dtype=np.float64)


class ExpSeries(_RatioSeries):
    """a^I (S14-S15): a_0 = a^b, a_(k+1) = a_k ln(a) / (k + 1); converges for any b.

    Args:
        a: the base, finite and > 0 (default e).

    Raises:
        ValueError: a not a finite real > 0.
    """

    def __init__(self, a: float = math.e):
        a = _finite_real("a", a)
        if a <= 0:
            raise ValueError(f"exp series a^I needs a > 0, got a={a}")
        self.a, self.ln_a = a, math.log(a)
        self.name = f"exp(a={a:g})"

    def function(self, I):
        return A.exp(self.ln_a * I)

    def a0(self, b):
        return A.exp(self.ln_a * b)

    def ratio(self, k, b):
        return self.ln_a / (k + 1.0)


class ReciprocalSeries(_RatioSeries):
    """a / I (S16-S17): a_0 = a / b, a_(k+1) = -a_k / b; converges where |b - I| < |b|.

    Args:
        a: the numerator, a finite real.
        lo, hi: the known range of I (both or neither): refuses fixed points that diverge on it,
            and a pilot b is clamped to b >= 0.55 hi (b <= 0.55 lo for a negative range).

    Raises:
        ValueError: a not finite, a bad range, or a range containing 0 (the pole).
    """

    def __init__(self, a: float = 1.0, lo=None, hi=None):
        self.a = _finite_real("a", a)
        self.lo, self.hi = _check_range(lo, hi)
        if self.lo is not None and self.lo <= 0.0 <= self.hi:
            raise ValueError(
                f"reciprocal a/I: the range [{self.lo}, {self.hi}] contains 0, where a/I has a "
                "pole; no expansion point converges on it"
            )
        self.name = f"reciprocal(a={self.a:g})"

    def function(self, I):
        return self.a / I

    def check_center(self, b):
        for bc in np.atleast_1d(np.asarray(b, dtype=np.float64)):
            if not np.isfinite(bc) or bc == 0.0:
                raise ValueError(f"reciprocal a/I: expansion point b={bc} must be finite and "
                                 "non-zero")
            if self.lo is None:
                continue
            if bc > 0:
                ok = 0.0 < self.lo and self.hi < 2.0 * bc
            else:
                ok = 2.0 * bc < self.lo and self.hi < 0.0
            if not ok:
                raise ValueError(
                    f"reciprocal a/I: expansion point b={bc} is outside the convergence region for "
                    f"I in [{self.lo}, {self.hi}]: the series needs |b - I| < |b| for every such "
                    "I, i.e. lo, hi and b of one sign and max|I| < 2|b| (here b must be "
                    f"{'> ' + str(self.hi / 2) if self.hi > 0 else '< ' + str(self.lo / 2)})"
                )

    def clamp_center(self, b):
        if self.lo is None:
            return A.select(A.abs(b) < TINY, b * 0.0 + TINY, b)
        if self.hi > 0:
            return A.maximum(b, PILOT_FRACTION * self.hi)
        return A.minimum(b, PILOT_FRACTION * self.lo)

    def a0(self, b):
        return self.a / b

    def ratio(self, k, b):
        return -1.0 / b


class PowerFunctionSeries(_RatioSeries):
    """I^p (Eq. 24 with p = 1/gamma): a_0 = b^p, a_(k+1) = a_k (p - k) / ((k + 1) b); needs b > 0
    and |b - I| <= |b| (strict for p < 0). An integer p > 0 terminates (degree p).

    Args:
        p: the power, finite and non-zero.
        lo, hi: the known range of I (both or neither), lo >= 0 (> 0 for p < 0): refuses fixed
            points that diverge on it; a pilot b is clamped to b >= max(0.55 hi, 1e-6).

    Raises:
        ValueError: p not finite or 0, a bad range, or a range reaching below 0 (or 0 for p < 0).
    """

    def __init__(self, p: float, lo=None, hi=None):
        self.p = _finite_real("p", p)
        if self.p == 0.0:
            raise ValueError("power series I^p needs p != 0 (I^0 = 1 needs no estimator)")
        self.lo, self.hi = _check_range(lo, hi)
        if self.lo is not None and (self.lo < 0.0 or (self.p < 0 and self.lo <= 0.0)):
            raise ValueError(
                f"power I^{self.p:g}: the range [{self.lo}, {self.hi}] reaches "
                f"{'below 0' if self.lo < 0 else '0'}, where the real power is not analytic"
            )
        if self.p > 0 and float(self.p).is_integer():
            self.degree = int(self.p)  # the binomial series terminates
        self.name = f"power(p={self.p:g})"

    def function(self, I):
        if A.is_drjit(I):
            return A.drjit().power(I, self.p)
        return np.power(I, self.p)

    def check_center(self, b):
        for bc in np.atleast_1d(np.asarray(b, dtype=np.float64)):
            if not (np.isfinite(bc) and bc > 0.0):
                raise ValueError(f"power I^{self.p:g}: expansion point b={bc} must be > 0 (real "
                                 "powers branch at 0)")
            if self.lo is None:
                continue
            ok = self.hi <= 2.0 * bc if self.p > 0 else self.hi < 2.0 * bc
            if not ok:
                raise ValueError(
                    f"power I^{self.p:g}: expansion point b={bc} is outside the convergence region "
                    f"for I in [{self.lo}, {self.hi}]: the binomial series needs |b - I| <= |b| "
                    f"(strict for p < 0), i.e. b >= hi/2 = {self.hi / 2}"
                )

    def clamp_center(self, b):
        lower = TINY if self.lo is None else max(PILOT_FRACTION * self.hi, TINY)
        return A.maximum(b, lower)

    def a0(self, b):
        if A.is_drjit(b):
            return A.drjit().power(b, self.p)
        return np.power(b, self.p)

    def ratio(self, k, b):
        return (self.p - k) / ((k + 1.0) * b)


# ---------------------------------------------------------------------------------------------
# finite series kept in a shift register


class _TableSeries(Series):
    @property
    def state_len(self):
        return self.degree + 1

    def advance(self, ctx, state, k, b):
        return tuple(state[1:]) + (ctx.vzero(),)


class PolynomialSeries(_TableSeries):
    """sum_k c_k (x - center)^k with float64 coefficients of shape (K+1,) or (K+1, C).

    Args:
        coeffs: c_0..c_K, shape (K+1,) or (K+1, C), finite.
        center: the point they are about: a finite scalar or per-channel vector.

    Raises:
        ValueError: a bad shape, values not finite, or coefficients and center of different
            channel counts.
    """

    def __init__(self, coeffs, center=0.0):
        c = np.asarray(coeffs, dtype=np.float64)
        if c.ndim not in (1, 2) or c.shape[0] < 1:
            raise ValueError("polynomial coefficients must have shape (K+1,) or (K+1, C), got "
                             f"{c.shape}")
        if not np.all(np.isfinite(c)):
            raise ValueError("polynomial coefficients must be finite")
        center = np.asarray(center, dtype=np.float64)
        if center.ndim > 1 or not np.all(np.isfinite(center)):
            raise ValueError("center must be a finite scalar or per-channel vector, got "
                             f"{center!r}")
        self.coeffs, self.center = c, center
        self.degree = c.shape[0] - 1
        chans = {c.shape[1] if c.ndim == 2 else None,
                 center.shape[0] if center.ndim == 1 else None} - {None}
        if len(chans) > 1:
            raise ValueError(f"coefficients for {c.shape[1]} channels but a center for "
                             f"{center.shape[0]}")
        self.channels = chans.pop() if chans else None
        self.name = f"polynomial(degree={self.degree})"

    def shifted(self, b) -> "PolynomialSeries":
        """The same polynomial with coefficients about a fixed b (float64 on the host).

        Args:
            b: the new center, a float or per-channel vector.

        Returns:
            A new PolynomialSeries about b.
        """
        b = np.asarray(b, dtype=np.float64)
        h = b - self.center
        rows = taylor_shift([self.coeffs[k] for k in range(self.degree + 1)], h)
        return PolynomialSeries(np.array(np.broadcast_arrays(*rows)), b)

    def coefficients(self, b, K=None):
        c = self.shifted(b).coeffs
        if K is not None:
            c = np.concatenate([c, np.zeros((max(0, K + 1 - len(c)),) + c.shape[1:])])[:K + 1]
        return c

    def function(self, x):
        y = x - (A.const_like(self.center, x) if self.center.ndim else float(self.center))
        out = 0.0
        for k in range(self.degree, -1, -1):
            ck = self.coeffs[k]
            out = out * y + (A.const_like(ck, x) if ck.ndim else float(ck))
        return out

    __call__ = function

    def start(self, ctx, b):
        h = b - ctx.vconst(self.center)
        rows = [ctx.value_array(self.coeffs[k]) for k in range(self.degree + 1)]
        return tuple(taylor_shift(rows, h))

    def start_fixed(self, ctx, b):
        c = self.shifted(b).coeffs
        return tuple(ctx.value_array(c[k]) for k in range(self.degree + 1))


class TaylorSeries(_TableSeries):
    """a_k = derivative(k, b) / k! for k <= order (S10 truncated, i.e. the Taylor fit S25 about
    b).

    Args:
        derivative: derivative(k, b) -> g^(k)(b), array-generic in b.
        order: the highest k (an integer >= 0).
        function: g itself, for `function` (exact values); None: unknown.

    Raises:
        ValueError: derivative not callable, or order not an integer >= 0.
    """

    def __init__(self, derivative, order: int, function=None):
        if not callable(derivative):
            raise ValueError("derivative must be a callable derivative(k, b) -> g^(k)(b), got "
                             f"{derivative!r}")
        if isinstance(order, bool) or not isinstance(order, (int, np.integer)) or order < 0:
            raise ValueError(f"order must be an integer >= 0, got {order!r}")
        self.derivative, self.degree, self._function = derivative, int(order), function
        self.name = f"taylor(order={self.degree})"

    def function(self, I):
        if self._function is None:
            raise ValueError("this Taylor series was built without function=g, so its exact value "
                             "is unknown")
        return self._function(I)

    def start(self, ctx, b):
        return tuple(ctx.vzero() + self.derivative(k, b) * (1.0 / math.factorial(k))
                     for k in range(self.degree + 1))

    def start_fixed(self, ctx, b):
        c = self.coefficients(b)
        return tuple(ctx.value_array(c[k]) for k in range(self.degree + 1))

    def coefficients(self, b, K=None):
        b = np.asarray(b, dtype=np.float64)
        c = np.array([np.asarray(self.derivative(k, b), dtype=np.float64) / math.factorial(k)
                      for k in range(self.degree + 1)])
        if K is not None:
            c = np.concatenate([c, np.zeros((max(0, K + 1 - len(c)),) + c.shape[1:])])[:K + 1]
        return c


# ---------------------------------------------------------------------------------------------
# factories


def exp_series(a: float = math.e) -> ExpSeries:
    """a^I; exp(I) by default.

    Args:
        a: the base, finite and > 0.

    Returns:
        ExpSeries(a).

    Raises:
        ValueError: a bad base.
    """
    return ExpSeries(a)


def reciprocal_series(a: float = 1.0, lo=None, hi=None) -> ReciprocalSeries:
    """a / I, with the known range [lo, hi] of I (optional) used to refuse divergent expansions.

    Args:
        a: the numerator; lo, hi: the known range of I, or None.

    Returns:
        ReciprocalSeries(a, lo, hi).

    Raises:
        ValueError: as the class.
    """
    return ReciprocalSeries(a, lo, hi)


def power_series(p: float, lo=None, hi=None) -> PowerFunctionSeries:
    """I^p via the binomial series about b.

    Args:
        p: the power (finite, non-zero); lo, hi: the known range of I, or None.

    Returns:
        PowerFunctionSeries(p, lo, hi).

    Raises:
        ValueError: as the class.
    """
    return PowerFunctionSeries(p, lo, hi)


def gamma_series(gamma: float = 2.2, lo=None, hi=None) -> PowerFunctionSeries:
    """Gamma correction I^(1/gamma).

    Args:
        gamma: the gamma, finite and non-zero (default 2.2); lo, hi: the known range of I, or None.

    Returns:
        PowerFunctionSeries(1 / gamma, lo, hi), named "gamma(1/...)".

    Raises:
        ValueError: gamma not finite or 0, or a bad range.
    """
    gamma = _finite_real("gamma", gamma)
    if gamma == 0.0:
        raise ValueError("gamma must be non-zero")
    s = PowerFunctionSeries(1.0 / gamma, lo, hi)
    s.name = f"gamma(1/{gamma:g})"
    return s


def taylor_series(derivative, order: int, function=None) -> TaylorSeries:
    """Taylor coefficients from derivative(k, b) -> g^(k)(b), k = 0..order (array-generic in b).

    Args:
        derivative: derivative(k, b) -> g^(k)(b); order: the highest k (>= 0).
        function: g itself, or None.

    Returns:
        TaylorSeries(derivative, order, function).

    Raises:
        ValueError: as the class.
    """
    return TaylorSeries(derivative, order, function)


def polynomial_series(coeffs, center=0.0) -> PolynomialSeries:
    """sum_k coeffs[k] (x - center)^k.

    Args:
        coeffs: shape (K+1,) or (K+1, C); center: a scalar or per-channel vector.

    Returns:
        PolynomialSeries(coeffs, center).

    Raises:
        ValueError: as the class.
    """
    return PolynomialSeries(coeffs, center)
