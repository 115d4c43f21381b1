"""Polynomial fits of a style function, and their change of basis to monomials about b.

Reference: West & Mukherjee, supplement S3, Eqs. S25-S28 (typos corrected). A fit h ~ g turns any g
into a polynomial whose h(I) the U-statistic or a power-series estimator estimates without bias (Eq.
17). [lo, hi] maps onto t in [-1, 1] (Bernstein: s in [0, 1]).

Fits: `chebyshev_fit(g, degree, lo=-1, hi=1, nodes="chebyshev", points=None)` (S27),
`legendre_fit(g, degree, lo=-1, hi=1, nodes="gauss", points=None)` (S28), `bernstein_fit(g, degree,
lo=0, hi=1)` (S26), `taylor_fit(derivative, degree, b)` (S25); g may be per-channel callables.
`Fit.to_monomial(b)` gives c_k with h(x) = sum_k c_k (x - b)^k; `Fit.series(center)` wraps it for
the estimators. Nodes, weights and conditioning: docs/design/polynomial_fits.md.
"""
from __future__ import annotations

import math

import numpy as np

from styletrace.estimators import arrays as A
from styletrace.estimators.coefficients import PolynomialSeries, taylor_shift

__all__ = [
    "Fit",
    "to_unit",
    "from_unit",
    "chebyshev_nodes",
    "even_nodes",
    "gauss_legendre",
    "chebyshev_basis",
    "legendre_basis",
    "chebyshev_fit",
    "legendre_fit",
    "bernstein_fit",
    "taylor_fit",
]

BASES = ("chebyshev", "legendre", "bernstein", "monomial")


def _check_degree(degree):
    if isinstance(degree, bool) or not isinstance(degree, (int, np.integer)) or degree < 0:
        raise ValueError(f"degree must be an integer >= 0, got {degree!r}")
    return int(degree)


def _check_interval(lo, hi):
    try:
        lo, hi = float(lo), float(hi)
    except (TypeError, ValueError):
        raise ValueError(f"lo and hi must be numbers, got lo={lo!r}, hi={hi!r}") from None
    if not (math.isfinite(lo) and math.isfinite(hi)) or not lo < hi:
        raise ValueError(f"the fit interval needs finite lo < hi, got lo={lo}, hi={hi}")
    return lo, hi


def to_unit(x, lo, hi):
    """[lo, hi] -> [-1, 1]: t = (2x - lo - hi) / (hi - lo).

    Args:
        x: numbers or arrays (numpy or Dr.Jit); lo, hi: the interval, lo < hi.

    Returns:
        t, of x's kind.
    """
    return (2.0 * x - (lo + hi)) * (1.0 / (hi - lo))


def from_unit(t, lo, hi):
    """[-1, 1] -> [lo, hi], the inverse of `to_unit`.

    Args:
        t: numbers or arrays (numpy or Dr.Jit); lo, hi: the interval.

    Returns:
        x = lo + (t + 1) (hi - lo) / 2, of t's kind.
    """
    return lo + (t + 1.0) * (0.5 * (hi - lo))


def chebyshev_nodes(n: int) -> np.ndarray:
    """cos((2j-1) pi / (2n)), j = 1..n, in ascending order.

    Args:
        n: the node count (>= 1).

    Returns:
        The nodes, numpy float64 (n,).
    """
    j = np.arange(1, n + 1)
    return np.sort(np.cos((2 * j - 1) * np.pi / (2 * n)))


def even_nodes(n: int) -> np.ndarray:
    """-1 + 2j/(n+1), j = 1..n: evenly spaced, strictly inside (-1, 1).

    Args:
        n: the node count (>= 1).

    Returns:
        The nodes, numpy float64 (n,).
    """
    return -1.0 + 2.0 * np.arange(1, n + 1) / (n + 1)


def gauss_legendre(n: int):
    """Gauss-Legendre nodes (ascending) and weights on [-1, 1] (Golub-Welsch eigenproblem).

    Args:
        n: the node count (>= 1); the rule is exact for polynomials of degree <= 2n - 1.

    Returns:
        (nodes, weights), numpy float64 (n,) each.
    """
    k = np.arange(1, n)
    beta = k / np.sqrt(4.0 * k * k - 1.0)
    nodes, vecs = np.linalg.eigh(np.diag(beta, 1) + np.diag(beta, -1))
    return nodes, 2.0 * vecs[0] ** 2


def chebyshev_basis(t, K: int) -> list:
    """[T_0(t), ..., T_K(t)] by T_(n+1) = 2t T_n - T_(n-1) (array-generic).

    Args:
        t: points in [-1, 1] (numpy or Dr.Jit); K: the highest degree (>= 0).

    Returns:
        A list of K + 1 arrays of t's kind.
    """
    T = [t * 0.0 + 1.0, t]
    for n in range(1, K):
        T.append(2.0 * t * T[n] - T[n - 1])
    return T[:K + 1]


def legendre_basis(t, K: int) -> list:
    """[P_0(t), ..., P_K(t)] by (n+1) P_(n+1) = (2n+1) t P_n - n P_(n-1) (array-generic).

    Args:
        t: points in [-1, 1] (numpy or Dr.Jit); K: the highest degree (>= 0).

    Returns:
        A list of K + 1 arrays of t's kind.
    """
    P = [t * 0.0 + 1.0, t]
    for n in range(1, K):
        P.append(((2 * n + 1) * t * P[n] - n * P[n - 1]) * (1.0 / (n + 1)))
    return P[:K + 1]


def _poly_mul_u(p):
    return np.concatenate([np.zeros((1,) + p.shape[1:]), p])


def _pad(p, n):
    return np.concatenate([p, np.zeros((n - len(p),) + p.shape[1:])]) if len(p) < n else p


class Fit:
    """A fitted polynomial h on [lo, hi] in one of BASES; made by the *_fit functions.

    Args:
        basis: one of BASES (Chebyshev and Legendre in t in [-1, 1], Bernstein in s in [0, 1]).
        coeffs: (D+1,) or (D+1, C) coefficients in that basis, stored float64.
        lo, hi: the fit interval, finite, lo < hi.
        center: the default expansion point (monomial basis: the point the coefficients are
            about, required); None: the interval's midpoint.
        label: the name shown; empty: made from basis, degree and interval.

    Raises:
        ValueError: an unknown basis, or a bad interval.
    """

    def __init__(self, basis: str, coeffs, lo: float, hi: float, center: float = None,
                 label: str = ""):
        if basis not in BASES:
            raise ValueError(f"unknown basis {basis!r}; allowed: {', '.join(BASES)}")
        self.basis = basis
        self.coeffs = np.asarray(coeffs, dtype=np.float64)
        self.lo, self.hi = _check_interval(lo, hi)
        self.degree = self.coeffs.shape[0] - 1
        self.channels = self.coeffs.shape[1] if self.coeffs.ndim == 2 else None
        if basis == "monomial":
            self.alpha, self.beta = 1.0, -float(center)
        elif basis == "bernstein":
            self.alpha, self.beta = 1.0 / (self.hi - self.lo), -self.lo / (self.hi - self.lo)
        else:
            self.alpha, self.beta = (2.0 / (self.hi - self.lo),
                                     -(self.hi + self.lo) / (self.hi - self.lo))
        self.center = float(center) if center is not None else 0.5 * (self.lo + self.hi)
        self.label = label or f"{basis}(degree={self.degree}, [{self.lo:g}, {self.hi:g}])"

    def __repr__(self):
        return f"<Fit {self.label}>"

    # -- evaluation -----------------------------------------------------------------------------
    def _c(self, i, x):
        c = self.coeffs[i]
        return A.const_like(c, x) if c.ndim else float(c)

    def __call__(self, x):
        """h(x), array-generic (numpy (..., C) or Dr.Jit values for per-channel fits)."""
        u = x * self.alpha + self.beta
        if self.basis in ("chebyshev", "legendre"):
            B = (chebyshev_basis(u, self.degree) if self.basis == "chebyshev"
                 else legendre_basis(u, self.degree))
            out = 0.0
            for i, Bi in enumerate(B):
                out = out + self._c(i, x) * Bi
            return out
        d = self.monomial_in_u()
        out = 0.0
        for k in range(self.degree, -1, -1):
            ck = d[k]
            out = out * u + (A.const_like(ck, x) if ck.ndim else float(ck))
        return out

    # -- change of basis --------------------------------------------------------------------------
    def monomial_in_u(self) -> np.ndarray:
        """Coefficients of u^k, u the basis variable (t for Chebyshev/Legendre, s for Bernstein)."""
        D, c = self.degree, self.coeffs
        tail = c.shape[1:]
        if self.basis == "monomial":
            return c.copy()
        out = np.zeros((D + 1,) + tail)
        if self.basis == "bernstein":
            for i in range(D + 1):
                for j in range(D - i + 1):
                    out[i + j] += math.comb(D, i) * math.comb(D - i, j) * (-1) ** j * c[i]
            return out
        prev, cur = np.ones((1,)), np.array([0.0, 1.0])
        polys = [prev, cur]
        for n in range(1, D):
            up = _poly_mul_u(polys[n])
            if self.basis == "chebyshev":
                nxt = 2.0 * up - _pad(polys[n - 1], n + 2)
            else:
                nxt = ((2 * n + 1) * up - n * _pad(polys[n - 1], n + 2)) / (n + 1)
            polys.append(nxt)
        for i in range(D + 1):
            p = _pad(polys[i], D + 1)
            out += p.reshape((D + 1,) + (1,) * len(tail)) * c[i]
        return out

    def to_monomial(self, b=None) -> np.ndarray:
        """c_k with h(x) = sum_k c_k (x - b)^k in the original variable x.

        Args:
            b: the expansion point; None: the fit's center.

        Returns:
            numpy float64 (D+1,) or (D+1, C).
        """
        b = self.center if b is None else float(b)
        d = self.monomial_in_u()
        ub = self.alpha * b + self.beta
        e = taylor_shift([d[k] for k in range(self.degree + 1)], ub)
        return np.array([e[k] * self.alpha ** k for k in range(self.degree + 1)])

    def series(self, center=None) -> PolynomialSeries:
        """The fit as sum_k c_k (x - center)^k for the polynomial / power-series estimators.

        Args:
            center: the expansion point; None: the fit's center.

        Returns:
            A `coefficients.PolynomialSeries`.
        """
        center = self.center if center is None else float(center)
        return PolynomialSeries(self.to_monomial(center), center)

    def max_error(self, g, points: int = 20001) -> np.ndarray:
        """max |h - g| over an even grid of [lo, hi] (per channel if g is a sequence).

        Args:
            g: the fitted callable, or one per channel.
            points: the grid's size.

        Returns:
            A float, or numpy (C,) for a per-channel fit.

        Raises:
            ValueError: g is not a callable or a sequence of callables.
        """
        x = np.linspace(self.lo, self.hi, points)
        gs = _callables(g)
        if self.channels is None:
            return float(np.max(np.abs(self(x) - gs[0](x))))
        X = np.repeat(x[:, None], self.channels, axis=1)
        H = self(X)
        return np.array([np.max(np.abs(H[:, c] - gs[c](x))) for c in range(self.channels)])


def _callables(g):
    gs = list(g) if isinstance(g, (list, tuple)) else [g]
    for f in gs:
        if not callable(f):
            raise ValueError(f"g must be a callable or a sequence of callables, got {f!r}")
    return gs


def _sample(g, x):
    gs = _callables(g)
    vals = [np.asarray(f(x), dtype=np.float64) * np.ones_like(x) for f in gs]
    return vals[0] if not isinstance(g, (list, tuple)) else np.stack(vals, axis=-1)


def _points(points, default):
    if points is None:
        return default
    if isinstance(points, bool) or not isinstance(points, (int, np.integer)) or points < 1:
        raise ValueError(f"points must be an integer >= 1, got {points!r}")
    return int(points)


def chebyshev_fit(g, degree: int, lo: float = -1.0, hi: float = 1.0, nodes: str = "chebyshev",
                  points=None) -> Fit:
    """Chebyshev fit (S27): a_i = sum_j g(x_j) T_i(t_j) w_j / C(i), C(0) = pi, C(i>0) = pi/2.

    Args:
        g: a callable on numpy arrays, or a sequence of per-channel callables; degree: D >= 0.
        lo, hi: the fit interval; points: the node count n (None: D + 1, or 4096 for even).
        nodes: "chebyshev" (interpolation, exact below degree n) or "even" (S27's literal weights).

    Returns:
        The Fit.

    Raises:
        ValueError: a bad degree, interval, nodes, points or g.
    """
    D = _check_degree(degree)
    lo, hi = _check_interval(lo, hi)
    if nodes == "chebyshev":
        n = _points(points, D + 1)
        t = chebyshev_nodes(n)
        w = np.full(n, np.pi / n)
    elif nodes == "even":
        n = _points(points, 4096)
        t = even_nodes(n)
        w = np.diff(np.concatenate([[-1.0], t])) / np.sqrt(1.0 - t * t)
    else:
        raise ValueError(f"unknown Chebyshev nodes {nodes!r}; allowed: 'chebyshev', 'even'")
    gv = _sample(g, from_unit(t, lo, hi))
    T = np.array(chebyshev_basis(t, D))
    C = np.full(D + 1, np.pi / 2)
    C[0] = np.pi
    a = (T * w) @ gv / (C if gv.ndim == 1 else C[:, None])
    return Fit("chebyshev", a, lo, hi, label=f"chebyshev(degree={D}, {nodes} nodes n={n}, [{lo:g}, "
                                             f"{hi:g}])")


def legendre_fit(g, degree: int, lo: float = -1.0, hi: float = 1.0, nodes: str = "gauss",
                 points=None) -> Fit:
    """Legendre fit (S28): a_i = (2i+1)/2 sum_j g(x_j) P_i(t_j) w_j.

    Args:
        g: a callable on numpy arrays, or a sequence of per-channel callables; degree: D >= 0.
        lo, hi: the fit interval; points: the node count n (None: D + 1, or 4096 for even).
        nodes: "gauss" (Gauss-Legendre, exact to degree 2n - 1) or "even" (S28's literal weights).

    Returns:
        The Fit.

    Raises:
        ValueError: a bad degree, interval, nodes, points or g.
    """
    D = _check_degree(degree)
    lo, hi = _check_interval(lo, hi)
    if nodes == "gauss":
        n = _points(points, D + 1)
        t, w = gauss_legendre(n)
    elif nodes == "even":
        n = _points(points, 4096)
        t = even_nodes(n)
        w = np.diff(np.concatenate([[-1.0], t]))
    else:
        raise ValueError(f"unknown Legendre nodes {nodes!r}; allowed: 'gauss', 'even'")
    gv = _sample(g, from_unit(t, lo, hi))
    P = np.array(legendre_basis(t, D))
    f = (2.0 * np.arange(D + 1) + 1.0) / 2.0
    a = (P * w) @ gv * (f if gv.ndim == 1 else f[:, None])
    return Fit("legendre", a, lo, hi, label=f"legendre(degree={D}, {nodes} nodes n={n}, [{lo:g}, "
                                            f"{hi:g}])")


def bernstein_fit(g, degree: int, lo: float = 0.0, hi: float = 1.0) -> Fit:
    """Bernstein fit (S26): h(x) = sum_i g(x_i) C(D, i) s^i (1 - s)^(D - i), x_i at s = i / D.

    Args:
        g: a callable g(x) -> y on numpy arrays, or a sequence of per-channel callables.
        degree: D >= 0; lo, hi: the fit interval (s = (x - lo) / (hi - lo)).

    Returns:
        The Fit.

    Raises:
        ValueError: a bad degree, interval or g.
    """
    D = _check_degree(degree)
    lo, hi = _check_interval(lo, hi)
    s = np.arange(D + 1) / D if D > 0 else np.zeros(1)
    gv = _sample(g, lo + s * (hi - lo))
    return Fit("bernstein", gv, lo, hi, label=f"bernstein(degree={D}, [{lo:g}, {hi:g}])")


def taylor_fit(derivative, degree: int, b: float, lo: float = None, hi: float = None) -> Fit:
    """Taylor polynomial about b (S25): h(x) = sum_i g^(i)(b) / i! (x - b)^i.

    Args:
        derivative: derivative(i, b) -> g^(i)(b) (a number, or one per channel).
        degree: D >= 0; b: the expansion point.
        lo, hi: where max_error looks (None: b - 1 and b + 1); no effect on h.

    Returns:
        The Fit (monomial basis, center b).

    Raises:
        ValueError: a bad degree or derivative.
    """
    D = _check_degree(degree)
    if not callable(derivative):
        raise ValueError("derivative must be a callable derivative(k, b) -> g^(k)(b), got "
                         f"{derivative!r}")
    b = float(b)
    c = np.array([np.asarray(derivative(k, b), dtype=np.float64) / math.factorial(k)
                  for k in range(D + 1)])
    lo = b - 1.0 if lo is None else lo
    hi = b + 1.0 if hi is None else hi
    return Fit("monomial", c, lo, hi, center=b, label=f"taylor(degree={D}, b={b:g})")
