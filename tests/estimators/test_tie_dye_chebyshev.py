"""Tie-dye (Fig. 11): the three channel functions and their degree-20 Chebyshev fit on [-1, 4]."""
import math

import numpy as np
import pytest

from styletrace.estimators import (
    TIE_DYE,
    Pilot,
    PolynomialU,
    Uniform,
    channel_means,
    tie_dye,
    tie_dye_b,
    tie_dye_fit,
    tie_dye_g,
    tie_dye_r,
)

from .estimator_stats import assert_unbiased, run_estimates

#: Stated maximum error of tie_dye_fit() (degree 20, Chebyshev nodes) on [-1, 4], per channel r, g,
#: b, measured on a 20001-point grid (4.4e-3, 2.3e-2, 6.0e-2) and rounded up. The blue channel has
#: the highest frequency (2.3 pi over an interval of length 5, about 5.75 periods), so degree 20
#: resolves it worst; degree 28 would give < 5e-5 on every channel.
TIE_DYE_MAX_ERROR = (5e-3, 2.5e-2, 6.5e-2)


def test_channel_functions_follow_the_supplement():
    x = np.array([-1.0, 0.0, 0.37, 4.0])
    np.testing.assert_allclose(tie_dye_r(x), (1 - np.cos(2 * math.pi * (x + 1))) / 2)
    np.testing.assert_allclose(tie_dye_g(x), (1 - np.cos(2.15 * math.pi * (x + 1.13))) / 2)
    np.testing.assert_allclose(tie_dye_b(x), (1 - np.cos(2.3 * math.pi * (x + 1.29))) / 2)
    np.testing.assert_allclose(
        tie_dye(np.stack([x, x, x], -1)), np.stack([f(x) for f in TIE_DYE], -1)
    )


def test_degree20_fit_holds_its_stated_maximum_error():
    fit = tie_dye_fit()
    assert fit.degree == 20 and (fit.lo, fit.hi) == (-1.0, 4.0) and fit.coeffs.shape == (21, 3)
    err = fit.max_error(list(TIE_DYE))
    assert np.all(err <= TIE_DYE_MAX_ERROR), err
    assert np.all(tie_dye_fit(28).max_error(list(TIE_DYE)) < 5e-5)


def test_fit_evaluates_the_same_on_drjit(jit):
    Array3f, Float = jit.Array3f, jit.Float
    fit = tie_dye_fit()
    x = np.linspace(-1, 4, 101)
    y = fit(np.stack([x, x, x], -1))
    X = Float(x)
    yd = np.asarray(fit(Array3f(X, X, X))).T
    td = np.asarray(tie_dye(Array3f(X, X, X))).T
    # float32 kernel: the Chebyshev recurrence keeps |T_i| <= 1, so rounding stays ~1e-6
    np.testing.assert_allclose(yd, y, atol=2e-5)
    np.testing.assert_allclose(td, tie_dye(np.stack([x, x, x], -1)), atol=1e-5)


def test_ustat_of_the_tie_dye_fit_is_unbiased_for_the_fit_per_channel():
    fit = tie_dye_fit()
    dist = Uniform(0.3, 0.5)  # channels get x, 2x, 3x: I = (0.4, 0.8, 1.2)
    est = PolynomialU(fit, n=20, b=Pilot(2))
    r = run_estimates(est, dist, 50_000, seed=11, channels=3)
    assert_unbiased(r.values, fit(channel_means(dist, 3)), what=est.name)


def test_fit_refuses_bad_parameters():
    with pytest.raises(ValueError, match="lo < hi"):
        tie_dye_fit(20, 4.0, -1.0)
