"""Truncation distributions: which terms of an infinite sum get evaluated, and with what weight.

Reference: Georgiev et al., "Integral Formulations of Volumetric Transmittance" (2019); Kettunen,
d'Eon, Pantaleoni, Novak, "An Unbiased Ray-Marching Transmittance Estimator" (2021). N is the last
term evaluated, S(k) = P(N >= k); a prefix sum weights term k by 1 / S(k), Russian roulette
continues with q_k = S(k) / S(k-1). Distributions: `Cumulative(min_continue=0)` (adaptive, recursive
selection only), `PoissonCMF(tau=2, threshold=0.99)`, `Poisson(tau=2)`, `Geometric(p=0.5,
min_terms=0)`, `PowerLaw(alpha=1.5, min_terms=0)`. Terms with S(k) < 2^-24 or beyond `max_terms` are
never evaluated: the estimate is unbiased for the series truncated there. Details:
docs/design/power_series.md.
"""
from __future__ import annotations

import math

import numpy as np

__all__ = ["Truncation", "Cumulative", "PoissonCMF", "Poisson", "Geometric", "PowerLaw",
           "resolve_truncation"]

#: A float32 uniform is a multiple of 2**-24, so a truncation decision cannot resolve probabilities
#: below this; terms the truncation would reach less often are never evaluated.
RESOLUTION = 2.0 ** -24


def _positive(name, v, upper=None):
    if (isinstance(v, bool) or not isinstance(v, (int, float, np.floating, np.integer))
            or not math.isfinite(v) or v <= 0):
        raise ValueError(f"{name} must be a positive finite number, got {v!r}")
    if upper is not None and v >= upper:
        raise ValueError(f"{name} must be < {upper}, got {v!r}")
    return float(v)


def _min_terms(v):
    if isinstance(v, bool) or not isinstance(v, (int, np.integer)) or v < 0:
        raise ValueError(f"min_terms must be an integer >= 0, got {v!r}")
    return int(v)


class Truncation:
    """The distribution of N, the last term evaluated, by its survival S(k) = P(N >= k), S(0) = 1;
    `adaptive` ones decide from the samples instead (Russian roulette only)."""

    adaptive = False
    name = "truncation"

    def survival(self, kmax: int) -> np.ndarray:
        """S(0..kmax) as float64.

        Args:
            kmax: the last k.

        Returns:
            numpy float64 (kmax + 1,).
        """
        raise NotImplementedError

    def cap(self, max_terms: int) -> int:
        """Largest k <= max_terms with S(k) >= 2^-24.

        Args:
            max_terms: the largest k wanted.

        Returns:
            K, the last term ever evaluated.
        """
        S = self.survival(max_terms)
        ok = np.flatnonzero(S >= RESOLUTION)
        return int(ok[-1])

    def tables(self, max_terms: int):
        """The tables the estimators look up, after the cap.

        Args:
            max_terms: the largest k wanted.

        Returns:
            (K, S[0..K], 1/S[0..K], q[0..K+1] with q_k = S(k)/S(k-1) and q_(K+1) = 0, pmf[0..K]).
        """
        K = self.cap(max_terms)
        S = self.survival(K + 1)
        q = np.ones(K + 2)
        q[1:] = S[1:] / S[:-1]
        q[K + 1] = 0.0  # the cap: never beyond K
        pmf = S[:K + 1] - np.append(S[1:K + 1], 0.0)
        return K, S[:K + 1], 1.0 / S[:K + 1], q, pmf

    def __repr__(self):
        return self.name


class Cumulative(Truncation):
    """Adaptive: after term k continue with probability clamp(W_k, min_continue, 1), W_k the
    running term weight relative to the zeroth term (recursive selection only).

    Args:
        min_continue: the floor on the continuation probability, in [0, 1]; use one > 0 for a
            series with an interior zero coefficient, which otherwise stops there.

    Raises:
        ValueError: min_continue outside [0, 1].
    """

    adaptive = True

    def __init__(self, min_continue: float = 0.0):
        if not (isinstance(min_continue, (int, float)) and 0.0 <= min_continue <= 1.0):
            raise ValueError(f"min_continue must be in [0, 1], got {min_continue!r}")
        self.min_continue = float(min_continue)
        self.name = "cumulative" + (f"(min={self.min_continue:g})" if self.min_continue else "")

    def survival(self, kmax):
        raise ValueError(
            "cumulative truncation adapts to the samples: it has no fixed distribution "
            "(use selection='recursive')"
        )

    def cap(self, max_terms):
        return max_terms


class PoissonCMF(Truncation):
    """Terms 0..K0 always, K0 the first k where the Poisson(tau) CMF reaches `threshold`; beyond,
    continue to term k with probability min(1, tau / k).

    Args:
        tau: the Poisson mean (> 0); threshold: the CMF level, in (0, 1).

    Raises:
        ValueError: either out of range.
    """

    def __init__(self, tau: float = 2.0, threshold: float = 0.99):
        self.tau = _positive("tau", tau)
        self.threshold = _positive("threshold", threshold, upper=1.0)
        cmf, pk, k = 0.0, math.exp(-self.tau), 0
        while True:
            cmf += pk
            if cmf >= self.threshold:
                break
            k += 1
            pk *= self.tau / k
        self.deterministic = k
        self.name = f"poisson-cmf(tau={self.tau:g}, K0={k})"

    def survival(self, kmax):
        S = np.ones(kmax + 1)
        for k in range(self.deterministic + 1, kmax + 1):
            S[k] = S[k - 1] * min(1.0, self.tau / k)
        return S


class Poisson(Truncation):
    """N ~ Poisson(tau), S(k) = P(N >= k): full support, usable by single-term selection.

    Args:
        tau: the mean (> 0, finite).

    Raises:
        ValueError: tau out of range.
    """

    def __init__(self, tau: float = 2.0):
        self.tau = _positive("tau", tau)
        self.name = f"poisson(tau={self.tau:g})"

    def survival(self, kmax):
        # far enough that the neglected tail is below float64 resolution
        M = kmax + 64 + int(10 * self.tau)
        pk = np.empty(M + 1)
        pk[0] = math.exp(-self.tau)
        for k in range(1, M + 1):
            pk[k] = pk[k - 1] * self.tau / k
        # S(k) = 1 - CMF(k-1); in the tail, summing the pmf is more accurate than 1 minus a CMF
        # near 1
        tail = np.cumsum(pk[::-1])[::-1]
        head = 1.0 - np.concatenate([[0.0], np.cumsum(pk)[:-1]])
        return np.where(head > 0.5, head, tail)[:kmax + 1]


class Geometric(Truncation):
    """S(k) = 1 for k <= min_terms, p^(k - min_terms) beyond.

    Args:
        p: the continuation probability, in (0, 1).
        min_terms: the terms always evaluated after the zeroth (an integer >= 0).

    Raises:
        ValueError: either out of range.
    """

    def __init__(self, p: float = 0.5, min_terms: int = 0):
        self.p = _positive("p", p, upper=1.0)
        self.min_terms = _min_terms(min_terms)
        self.name = f"geometric(p={self.p:g}, min={self.min_terms})"

    def survival(self, kmax):
        k = np.arange(kmax + 1)
        return np.where(k <= self.min_terms, 1.0, self.p ** np.maximum(k - self.min_terms, 0))


class PowerLaw(Truncation):
    """S(k) = 1 for k <= min_terms, (k - min_terms + 1)^(-alpha) beyond: heavy tails (telescoping).

    Args:
        alpha: the tail exponent (> 0, finite).
        min_terms: the terms always evaluated after the zeroth (an integer >= 0).

    Raises:
        ValueError: either out of range.
    """

    def __init__(self, alpha: float = 1.5, min_terms: int = 0):
        self.alpha = _positive("alpha", alpha)
        self.min_terms = _min_terms(min_terms)
        self.name = f"power-law(alpha={self.alpha:g}, min={self.min_terms})"

    def survival(self, kmax):
        k = np.arange(kmax + 1)
        return np.where(k <= self.min_terms, 1.0,
                        (np.maximum(k - self.min_terms, 0) + 1.0) ** -self.alpha)


_NAMES = {"cumulative": Cumulative, "poisson_cmf": PoissonCMF, "poisson": Poisson,
          "geometric": Geometric, "power_law": PowerLaw}


def resolve_truncation(spec) -> Truncation:
    """A Truncation instance from an instance or a name (default parameters).

    Args:
        spec: a Truncation, or one of "cumulative", "poisson_cmf", "poisson", "geometric",
            "power_law".

    Returns:
        The Truncation.

    Raises:
        ValueError: anything else.
    """
    if isinstance(spec, Truncation):
        return spec
    if isinstance(spec, str) and spec in _NAMES:
        return _NAMES[spec]()
    raise ValueError(f"unknown truncation {spec!r}; allowed: a Truncation instance or one of "
                     f"{sorted(_NAMES)}")
