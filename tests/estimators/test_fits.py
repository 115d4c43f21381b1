"""Polynomial fits (S25-S28): agreement with numpy.polynomial, change of basis, fitted
estimators."""
import math
from fractions import Fraction

import numpy as np
import pytest
from numpy.polynomial import chebyshev as npcheb
from numpy.polynomial import legendre as npleg

from styletrace.estimators import (
    Pilot,
    PolynomialU,
    SeriesEstimator,
    Uniform,
    bernstein_fit,
    chebyshev_fit,
    from_unit,
    legendre_fit,
    taylor_fit,
    to_unit,
)

from .estimator_stats import BACKENDS, assert_unbiased, run_estimates

EPS = np.finfo(np.float64).eps
FUNCS = {
    "exp-sin": (lambda x: np.exp(-x) * np.sin(3 * x), 0.0, 2.0),
    "runge": (lambda x: 1.0 / (1.0 + 4.0 * x * x), -1.0, 1.0),
    "cos": (lambda x: np.cos(5 * x + 0.3), -1.0, 4.0),
}


def on_unit(g, lo, hi):
    return lambda t: g(from_unit(t, lo, hi))


def test_domain_mapping_round_trip_and_end_points():
    x = np.linspace(-1.0, 4.0, 11)
    np.testing.assert_allclose(from_unit(to_unit(x, -1.0, 4.0), -1.0, 4.0), x, atol=1e-14)
    assert to_unit(-1.0, -1.0, 4.0) == -1.0 and to_unit(4.0, -1.0, 4.0) == 1.0


@pytest.mark.parametrize("name", list(FUNCS))
@pytest.mark.parametrize("degree", [0, 3, 12, 20])
def test_chebyshev_nodes_fit_is_numpy_chebinterpolate(name, degree):
    g, lo, hi = FUNCS[name]
    fit = chebyshev_fit(g, degree, lo, hi)
    want = npcheb.chebinterpolate(on_unit(g, lo, hi), degree)
    # both are the discrete Chebyshev transform at the same degree+1 nodes: sums of n = degree+1
    # terms bounded by max|g|, so rounding differs by at most ~n eps max|g|
    tol = 4 * (degree + 1) * EPS * max(1.0, np.max(np.abs(want)) * (degree + 1))
    np.testing.assert_allclose(fit.coeffs, want, atol=tol, rtol=0)


def test_chebyshev_nodes_with_more_points_truncate_the_larger_interpolant():
    g, lo, hi = FUNCS["cos"]
    fit = chebyshev_fit(g, 10, lo, hi, points=31)
    want = npcheb.chebinterpolate(on_unit(g, lo, hi), 30)[:11]  # discrete orthogonality for i < n
    np.testing.assert_allclose(fit.coeffs, want, atol=1e-13)


@pytest.mark.parametrize("name", ["exp-sin", "cos"])
def test_chebyshev_even_nodes_riemann_sum_converges_to_the_projection(name):
    g, lo, hi = FUNCS[name]
    D = 8
    # projection coefficients (analytic g)
    proj = npcheb.chebinterpolate(on_unit(g, lo, hi), 200)[:D + 1]
    gmax = np.max(np.abs(g(np.linspace(lo, hi, 10001))))
    errs = []
    for n in (1024, 16384):
        fit = chebyshev_fit(g, D, lo, hi, nodes="even", points=n)
        err = np.max(np.abs(fit.coeffs - proj))
        # The weight 1/sqrt(1-t^2) is integrable but unbounded: the two end cells of width h =
        # 2/(n+1) hold mass ~sqrt(2h) each that the Riemann sum gets wrong by O(1), and the interior
        # rule's error (h times the variation of the weighted integrand) is of the same order; with
        # |T_i| <= 1 and 1/C(i) <= 2/pi: |error| <= 4 sqrt(2h) max|g| 2/pi.
        h = 2.0 / (n + 1)
        assert err <= 4 * math.sqrt(2 * h) * gmax * 2 / math.pi
        errs.append(err)
    assert errs[1] < errs[0] / 2  # O(n^-1/2): 16x the points, about 1/4 of the error


@pytest.mark.parametrize("n_extra", [0, 9])
@pytest.mark.parametrize("name", list(FUNCS))
def test_legendre_gauss_fit_is_numpy_weighted_least_squares(name, n_extra):
    g, lo, hi = FUNCS[name]
    D = 12
    n = D + 1 + n_extra
    fit = legendre_fit(g, D, lo, hi, points=n)
    t, w = npleg.leggauss(n)
    want = npleg.legfit(t, on_unit(g, lo, hi)(t), D, w=np.sqrt(w))
    # Gauss quadrature with n >= D+1 nodes integrates P_i P_k exactly (degree <= 2n-1), so the
    # discrete projection is the weighted least-squares fit at those nodes. numpy solves that by
    # lstsq on a Vandermonde matrix whose condition number is O(D) here: agreement to ~1e3 eps
    # max|a|.
    np.testing.assert_allclose(
        fit.coeffs, want, atol=1e3 * EPS * max(1.0, np.max(np.abs(want))), rtol=0
    )


def test_legendre_even_riemann_sum_is_first_order_accurate():
    g, lo, hi = FUNCS["exp-sin"]
    D = 6
    t, w = npleg.leggauss(200)
    proj = npleg.legfit(t, on_unit(g, lo, hi)(t), D, w=np.sqrt(w))
    n = 4096
    fit = legendre_fit(g, D, lo, hi, nodes="even", points=n)
    h = 2.0 / (n + 1)
    tt = np.linspace(-1, 1, 200001)
    for i in range(D + 1):
        f = on_unit(g, lo, hi)(tt) * npleg.legval(tt, np.eye(D + 1)[i])
        tv = np.sum(np.abs(np.diff(f)))
        # right Riemann sum on an interior grid: error <= h TV(f) (interior) + 2 h max|f| (the two
        # end cells [-1, t_1] and [t_n, 1]), times the (2i+1)/2 normalization
        bound = (2 * i + 1) / 2 * (h * tv + 2 * h * np.max(np.abs(f)))
        assert abs(fit.coeffs[i] - proj[i]) <= bound


def test_chebyshev_and_legendre_fits_converge_to_the_same_function():
    g, lo, hi = FUNCS["exp-sin"]
    c, leg = chebyshev_fit(g, 16, lo, hi), legendre_fit(g, 16, lo, hi)
    x = np.linspace(lo, hi, 1001)
    assert np.max(np.abs(c(x) - g(x))) < 1e-9 and np.max(np.abs(leg(x) - g(x))) < 1e-9


def test_bernstein_fit_is_the_s26_sum():
    g = lambda x: np.sqrt(x + 0.1)  # noqa: E731
    k, lo, hi = 7, 0.0, 2.0
    fit = bernstein_fit(g, k, lo, hi)
    x = np.linspace(lo, hi, 57)
    s = (x - lo) / (hi - lo)
    want = sum(
        g(lo + i / k * (hi - lo)) * math.comb(k, i) * s**i * (1 - s) ** (k - i)
        for i in range(k + 1)
    )
    np.testing.assert_allclose(fit(x), want, rtol=1e-12, atol=1e-12)


def test_taylor_fit_coefficients_are_derivatives_over_factorials():
    fit = taylor_fit(lambda k, b: np.exp(b), 6, b=0.5)
    np.testing.assert_allclose(
        fit.coeffs, [math.exp(0.5) / math.factorial(k) for k in range(7)], rtol=1e-15
    )
    np.testing.assert_allclose(fit.to_monomial(0.5), fit.coeffs, rtol=1e-15)


def basis_to_monomial_exact(fit):
    """Exact rational matrix B with u^k coefficient of basis function i in B[k][i] (u = t, s or x
    - c)."""
    D = fit.degree
    B = [[Fraction(0)] * (D + 1) for _ in range(D + 1)]
    if fit.basis == "monomial":
        for i in range(D + 1):
            B[i][i] = Fraction(1)
        return B
    if fit.basis == "bernstein":
        for i in range(D + 1):
            for j in range(D - i + 1):
                B[i + j][i] += math.comb(D, i) * math.comb(D - i, j) * (-1) ** j
        return B
    polys = [[Fraction(1)], [Fraction(0), Fraction(1)]]
    for n in range(1, D):
        up = [Fraction(0)] + polys[n]
        prev = polys[n - 1] + [Fraction(0)] * 2
        if fit.basis == "chebyshev":
            polys.append([2 * up[k] - prev[k] for k in range(n + 2)])
        else:
            polys.append([((2 * n + 1) * up[k] - n * prev[k]) / (n + 1) for k in range(n + 2)])
    for i in range(D + 1):
        for k, v in enumerate(polys[i]):
            B[k][i] = v
    return B


def shift_exact(fit, b):
    """Exact S with (x - b)^k coefficient = sum_j S[k][j] u^j coefficient, u = alpha x + beta."""
    D = fit.degree
    alpha, beta = Fraction(fit.alpha), Fraction(fit.beta)
    ub = alpha * Fraction(b) + beta
    return [
        [
            math.comb(j, k) * ub ** (j - k) * alpha**k if j >= k else Fraction(0)
            for j in range(D + 1)
        ]
        for k in range(D + 1)
    ]


@pytest.mark.parametrize("make", [
    lambda: chebyshev_fit(FUNCS["cos"][0], 14, -1.0, 4.0),
    lambda: legendre_fit(FUNCS["cos"][0], 14, -1.0, 4.0),
    lambda: bernstein_fit(FUNCS["cos"][0], 9, -1.0, 4.0),
    lambda: taylor_fit(lambda k, b: 5.0 ** k * np.cos(5 * b + 0.3 + k * np.pi / 2), 9, b=1.0),
])
@pytest.mark.parametrize("b", [-1.0, 0.3, 1.5, 4.0])
def test_change_of_basis_gives_coefficients_about_b_in_the_original_variable(make, b):
    fit = make()
    D = fit.degree
    c = fit.to_monomial(b)
    B, S = basis_to_monomial_exact(fit), shift_exact(fit, b)
    a = [Fraction(float(v)) for v in fit.coeffs]
    mono = [sum(B[k][i] * a[i] for i in range(D + 1)) for k in range(D + 1)]
    exact = [float(sum(S[k][j] * mono[j] for j in range(D + 1))) for k in range(D + 1)]
    # floating-point matrix products: |error| <= ~2 (D+1) eps (|S| |B| |a|) per coefficient, doubled
    # for the two stages and the float64 rounding of alpha, beta and the shift point
    absa = [abs(v) for v in a]
    absmono = [sum(abs(B[k][i]) * absa[i] for i in range(D + 1)) for k in range(D + 1)]
    bound = [
        4 * (D + 1) * EPS * float(sum(abs(S[k][j]) * absmono[j] for j in range(D + 1)))
        for k in range(D + 1)
    ]
    assert np.all(np.abs(c - exact) <= np.array(bound) + 1e-300)
    # and the polynomial about b is the fit itself (up to that conversion error and the
    # evaluation's)
    x = np.linspace(fit.lo, fit.hi, 301)
    y = fit.series(b)(x)
    tol = sum((bound[k] + 8 * (D + 1) * EPS * abs(c[k])) * np.abs(x - b) ** k for k in range(D + 1))
    # the basis recurrence's own rounding
    tol = tol + 8 * (D + 1) ** 2 * EPS * float(np.sum(np.abs(fit.coeffs)))
    assert np.all(np.abs(y - fit(x)) <= tol)


def test_per_channel_fits_keep_channels_apart():
    gs = [np.sin, np.cos, np.exp]
    fit = chebyshev_fit(gs, 10, 0.0, 1.0)
    assert fit.coeffs.shape == (11, 3)
    x = np.linspace(0, 1, 5)
    y = fit(np.repeat(x[:, None], 3, axis=1))
    for c, f in enumerate(gs):
        np.testing.assert_allclose(y[:, c], f(x), atol=1e-9)


@pytest.mark.parametrize("backend", BACKENDS)
def test_fitted_chebyshev_estimators_are_unbiased_for_the_fit(backend):
    g, lo, hi = FUNCS["exp-sin"]
    fit = chebyshev_fit(g, 6, lo, hi)
    dist = Uniform(0.6, 1.4)
    exact = fit(dist.mean)  # the fit's own value: the estimator's error is the fit error, not noise
    for est in (PolynomialU(fit, n=8), PolynomialU(fit, n=6, b=Pilot(1)),
                SeriesEstimator(fit, b=Pilot(1), selection="iterative")):
        r = run_estimates(est, dist, 200_000, backend=backend, seed=3)
        assert_unbiased(r.values, exact, what=est.name)


def test_invalid_fit_parameters_name_the_value():
    g = np.sin
    with pytest.raises(ValueError, match="degree must be an integer >= 0, got -1"):
        chebyshev_fit(g, -1)
    with pytest.raises(ValueError, match="lo < hi, got lo=2.0, hi=1.0"):
        chebyshev_fit(g, 3, 2.0, 1.0)
    with pytest.raises(ValueError, match="unknown Chebyshev nodes 'gauss'"):
        chebyshev_fit(g, 3, nodes="gauss")
    with pytest.raises(ValueError, match="unknown Legendre nodes"):
        legendre_fit(g, 3, nodes="chebyshev")
    with pytest.raises(ValueError, match="points must be an integer >= 1"):
        legendre_fit(g, 3, points=0)
