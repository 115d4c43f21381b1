"""Coefficient generators: closed forms (S15, S17, Eq. 24), Taylor shift, convergence refusals."""
import math

import numpy as np
import pytest

from styletrace.estimators import (
    exp_series,
    gamma_series,
    polynomial_series,
    power_series,
    reciprocal_series,
    taylor_series,
    taylor_shift,
)


def gen_binom(p, k):
    return math.prod(p - j for j in range(k)) / math.factorial(k)


def test_exp_coefficients_are_s15():
    s = exp_series(2.0)
    b = 0.7
    want = [math.log(2.0) ** k * 2.0 ** b / math.factorial(k) for k in range(12)]
    np.testing.assert_allclose(s.coefficients(b, 11), want, rtol=1e-13)
    assert s.function(0.3) == pytest.approx(2.0 ** 0.3, rel=1e-15)


def test_reciprocal_coefficients_are_s17():
    s = reciprocal_series(3.0)
    b = 0.8
    # a/I = sum_k a b^(-k-1) (b - I)^k: the coefficient of (I - b)^k is a (-1)^k b^(-k-1)
    want = [3.0 * (-1) ** k * b ** (-k - 1) for k in range(10)]
    np.testing.assert_allclose(s.coefficients(b, 9), want, rtol=1e-13)
    I = 0.6
    assert sum(c * (I - b) ** k for k, c in enumerate(s.coefficients(b, 200))) == pytest.approx(
        3.0 / I, rel=1e-12
    )


@pytest.mark.parametrize("gamma", [2.2, 1.0 / 3.0, -2.0])
def test_power_coefficients_are_generalized_binomials(gamma):
    s = gamma_series(gamma)
    p, b = 1.0 / gamma, 1.3
    want = [gen_binom(p, k) * b ** (p - k) for k in range(10)]
    np.testing.assert_allclose(s.coefficients(b, 9), want, rtol=1e-12)
    I = 1.0
    assert sum(c * (I - b) ** k for k, c in enumerate(s.coefficients(b, 200))) == pytest.approx(
        I**p, rel=1e-12
    )


def test_integer_power_series_is_finite():
    assert power_series(3.0).degree == 3 and power_series(2.5).degree is None
    np.testing.assert_allclose(
        power_series(2.0).coefficients(0.5, 4), [0.25, 1.0, 1.0, 0.0, 0.0], atol=1e-15
    )


def test_taylor_series_from_a_derivative_callable():
    s = taylor_series(lambda k, b: np.sin(b + k * np.pi / 2), 7, function=np.sin)  # d^k/dx^k sin
    b = 0.4
    want = [math.sin(b + k * math.pi / 2) / math.factorial(k) for k in range(8)]
    np.testing.assert_allclose(s.coefficients(b), want, rtol=1e-12, atol=1e-15)
    assert s.degree == 7 and s.function(0.1) == math.sin(0.1)
    with pytest.raises(ValueError, match="without function=g"):
        taylor_series(lambda k, b: 1.0, 2).function(0.0)


def test_taylor_shift_moves_the_expansion_point():
    c = [1.0, -2.0, 0.5, 3.0]  # about 0
    shifted = taylor_shift(c, 0.7)
    x = np.linspace(-2, 2, 9)
    np.testing.assert_allclose(sum(s * (x - 0.7) ** k for k, s in enumerate(shifted)),
                               sum(a * x ** k for k, a in enumerate(c)), rtol=1e-13, atol=1e-13)
    p = polynomial_series(c, center=0.0)
    np.testing.assert_allclose(p.shifted(0.7).coeffs, shifted, rtol=1e-15)
    lanes = np.array([[0.1], [0.5], [-1.0]])  # per-lane shift points (array-generic)
    per_lane = taylor_shift([np.full((3, 1), v) for v in c], lanes)
    np.testing.assert_allclose(
        np.hstack(per_lane), np.array([taylor_shift(c, float(h)) for h in lanes[:, 0]])
    )


def test_reciprocal_refuses_expansion_points_outside_the_convergence_region():
    s = reciprocal_series(1.0, lo=0.5, hi=2.0)
    s.check_center(1.01)  # 2.0 < 2 * 1.01: every I in [0.5, 2] has |b - I| < |b|
    with pytest.raises(
        ValueError,
        match=r"b=0.9 is outside the convergence region for I in \[0.5, 2.0\].*\|b - I\| < \|b\|",
    ):
        s.check_center(0.9)
    with pytest.raises(ValueError, match=r"b must be > 1.0"):
        s.check_center(1.0)  # I = 2 = 2b sits on the boundary: the series does not converge there
    with pytest.raises(ValueError, match="outside the convergence region"):
        s.check_center(-1.0)
    neg = reciprocal_series(1.0, lo=-2.0, hi=-0.5)
    neg.check_center(-1.5)
    with pytest.raises(ValueError, match="b must be < -1.0"):
        neg.check_center(-0.9)
    with pytest.raises(ValueError, match="contains 0"):
        reciprocal_series(1.0, lo=-0.1, hi=1.0)
    with pytest.raises(ValueError, match="must be finite and non-zero"):
        reciprocal_series(1.0).check_center(0.0)
    with pytest.raises(ValueError, match="give both lo and hi"):
        reciprocal_series(1.0, lo=0.5)


def test_pilot_expansion_points_are_clamped_into_the_region():
    s = reciprocal_series(1.0, lo=0.5, hi=2.0)
    b = s.clamp_center(np.array([0.2, 1.0, 3.0]))
    np.testing.assert_allclose(b, [1.1, 1.1, 3.0])  # 0.55 hi: worst ratio |b - I|/|b| = 0.82 < 1
    g = gamma_series(2.2, lo=0.0, hi=4.0)
    np.testing.assert_allclose(g.clamp_center(np.array([0.0, 3.0])), [2.2, 3.0])
    assert gamma_series(2.2).clamp_center(np.array([-1.0]))[0] > 0


def test_power_series_checks():
    g = gamma_series(2.2, lo=0.0, hi=1.0)
    # I = 0 and I = 1 sit on |b - I| = |b|, where sum |C(p, k)| converges for p > 0
    g.check_center(0.5)
    with pytest.raises(ValueError, match="b >= hi/2 = 0.5"):
        g.check_center(0.4)
    with pytest.raises(ValueError, match="must be > 0"):
        gamma_series(2.2).check_center(0.0)
    with pytest.raises(ValueError, match="below 0"):
        gamma_series(2.2, lo=-0.5, hi=1.0)
    with pytest.raises(ValueError, match="p != 0"):
        power_series(0.0)
    with pytest.raises(ValueError, match="gamma must be non-zero"):
        gamma_series(0.0)
    with pytest.raises(ValueError, match="a > 0"):
        exp_series(-1.0)
    with pytest.raises(ValueError, match="lo <= hi"):
        gamma_series(2.2, lo=2.0, hi=1.0)
