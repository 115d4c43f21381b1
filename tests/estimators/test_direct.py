"""Direct application g(<I>_n): the delta-method bias, and that unbiasedness checks reject it."""
import math

import numpy as np
import pytest

from styletrace.estimators import Direct, Exponential, Uniform

from .estimator_stats import DISTS, Z, assert_detectably_biased, run_estimates, variance_and_se


def test_bias_matches_the_delta_method():
    # g = exp on U(0, 1), n = 8: predicted bias g''(I) Var / (2n) = e^0.5 / 192 = 8.6e-3. The exact
    # bias is known too, E[exp(<I>_n)] = (n (e^(1/n) - 1))^n: the delta method's remainder
    # (4th-order, the 3rd central moment of U is 0) is 2e-5 here, far below the standard error
    # (2.7e-4), so the comparison with the prediction is limited by noise only.
    dist, n, lanes = Uniform(0.0, 1.0), 8, 400_000
    r = run_estimates(Direct(np.exp, n), dist, lanes, seed=3)
    measured = r.values.mean() - math.exp(dist.mean)
    predicted = math.exp(dist.mean) * dist.var / (2 * n)
    exact_bias = (n * (math.exp(1 / n) - 1)) ** n - math.exp(dist.mean)
    assert abs(exact_bias - predicted) < 0.2 * r.stderr
    assert abs(measured - predicted) <= Z * r.stderr
    assert measured > Z * r.stderr  # resolvable: the bias is many standard errors away from 0


@pytest.mark.parametrize("n", [1, 4, 16])
def test_quadratic_bias_is_var_over_n(n):
    # g = x^2: the delta method is exact, E[<I>_n^2] = I^2 + Var/n
    dist = DISTS["exponential"]
    r = run_estimates(Direct(lambda x: x * x, n), dist, 200_000, seed=n)
    assert abs(r.values.mean() - (dist.mean ** 2 + dist.var / n)) <= Z * r.stderr
    assert_detectably_biased(r.values, dist.mean ** 2, what=f"direct x^2 n={n}")
    assert np.all(r.draws == n)


def test_direct_on_drjit_matches_numpy():
    dist = DISTS["uniform"]
    a = run_estimates(Direct(lambda x: x * x, 3), dist, 200_000, backend="numpy", seed=1)
    b = run_estimates(
        Direct(lambda x: x * x, 3), dist, 200_000, backend="drjit", seed=1, channels=3
    )
    want = (dist.mean * np.arange(1, 4)) ** 2 + dist.var * np.arange(1, 4) ** 2 / 3
    assert abs(a.values.mean() - want[0]) <= Z * a.stderr
    assert np.all(np.abs(b.values.mean(axis=0) - want) <= Z * b.stderr)


def test_comb_stratification_cuts_the_variance_of_the_mean():
    # for U(0, 1) a comb's mean is xi/m + (m-1)/(2m): variance 1/(12 m^2) instead of 1/(12 m)
    m = 8
    iid = run_estimates(Direct(lambda x: x, m), Uniform(0, 1), 100_000, seed=4).values
    comb = run_estimates(Direct(lambda x: x, m, comb=True), Uniform(0, 1), 100_000, seed=4).values
    (vi, si), (vc, sc) = variance_and_se(iid), variance_and_se(comb)
    assert abs(vi - 1 / (12 * m)) <= Z * si and abs(vc - 1 / (12 * m * m)) <= Z * sc
    assert abs(comb.mean() - 0.5) <= Z * math.sqrt(vc / len(comb))


def test_invalid_parameters():
    with pytest.raises(ValueError, match="n must be an integer >= 1, got 0"):
        Direct(np.exp, 0)
    with pytest.raises(ValueError, match="n must be an integer >= 1, got -3"):
        Direct(np.exp, -3)
    with pytest.raises(ValueError, match="g must be a callable"):
        Direct(2.0, 4)
    assert Direct(np.exp, 5).mean_draws == 5 and Direct(np.exp, 5).exact(0.0) == 1.0
    assert Exponential(2.0).mean == 2.0
