"""Telescoping debiasing of the direct estimator (Eq. 15 form)."""
import numpy as np
import pytest

from styletrace.estimators import Direct, Geometric, PowerLaw, Telescoping, TwoPoint

from .estimator_stats import DISTS, Z, assert_unbiased, run_estimates


@pytest.mark.parametrize("name", list(DISTS))
def test_telescoping_is_unbiased_where_direct_is_not(name):
    dist = DISTS[name]
    g = lambda x: x * x  # noqa: E731  the cap's residual bias Var/(n0+K) ~ 1e-6 is far below the stderr
    tel = Telescoping(g, n0=2)
    r = run_estimates(tel, dist, 200_000, seed=9)
    assert_unbiased(r.values, dist.mean ** 2, what=f"{tel.name} {name}")
    d = r.draws.astype(float)
    assert abs(d.mean() - tel.mean_draws) <= Z * d.std() / np.sqrt(len(d))


def test_telescoping_removes_a_bias_the_same_test_detects_in_direct():
    # I = 0, g = x^2, symmetric +-1 samples: g'(I) = 0, so the differences are second order and the
    # estimate is precise enough to see that the direct estimator's bias 1/n0 is gone.
    dist = TwoPoint(-1.0, 1.0, 0.5)
    g = lambda x: x * x  # noqa: E731
    r = run_estimates(Telescoping(g, n0=1, truncation=PowerLaw(1.5)), dist, 200_000, seed=1)
    assert_unbiased(r.values, 0.0)
    assert abs(r.values.mean()) + Z * r.stderr < 0.1  # the test resolves biases far below direct's
    direct = run_estimates(Direct(g, 1), dist, 1000, seed=1).values
    assert np.all(direct == 1.0)  # g(x) = 1 for every single sample: bias 1, with zero variance


def test_light_tailed_truncation_caps_early_and_keeps_the_capped_bias():
    # Geometric(0.5) reaches at most K = 24 differences: the expectation is E[g(<I>_(n0+K))] = I^2 +
    # Var/(n0+K)
    dist = DISTS["two-point"]
    tel = Telescoping(lambda x: x * x, n0=1, truncation=Geometric(0.5))
    assert tel.K == 24
    r = run_estimates(tel, dist, 200_000, seed=3)
    assert_unbiased(r.values, dist.mean ** 2 + dist.var / (1 + tel.K))


def test_invalid_parameters():
    with pytest.raises(ValueError, match="n0 must be an integer >= 1, got 0"):
        Telescoping(np.exp, n0=0)
    with pytest.raises(ValueError, match="adapts"):
        Telescoping(np.exp, truncation="cumulative")
    with pytest.raises(ValueError, match="g must be a callable"):
        Telescoping(None)
