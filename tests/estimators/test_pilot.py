"""Expansion points from pilot samples: independent of the terms, counted, clamped."""
import numpy as np
import pytest

from estimator_stats import DISTS, assert_unbiased, run_estimates
from styletrace.estimators import Pilot, PolynomialU, SeriesEstimator, gamma_series
from styletrace.estimators.pilot import ExpansionPoint


def test_pilot_samples_are_counted_and_separate():
    est = SeriesEstimator(gamma_series(2.2, lo=0.2, hi=1.0), b=Pilot(3))
    dist = DISTS["uniform"]
    r = run_estimates(est, dist, 100_000, seed=12)
    assert r.draws.min() >= 3 and est.mean_samples == pytest.approx(3 + np.sum(est.S[1:]))
    assert_unbiased(r.values, dist.mean ** (1 / 2.2))


def test_pilot_clamp_bounds_are_applied_before_the_series_clamp():
    dist = DISTS["exponential"]
    est = PolynomialU([1.0, 2.0, 3.0], n=2, b=Pilot(1, lo=0.3, hi=0.35))
    r = run_estimates(est, dist, 50_000, seed=1)
    assert_unbiased(r.values, 1 + 2 * dist.mean + 3 * dist.mean ** 2)


def test_invalid_pilots_and_points():
    with pytest.raises(ValueError, match="pilot n must be an integer >= 1, got 0"):
        Pilot(0)
    with pytest.raises(ValueError, match="lo < hi"):
        Pilot(1, lo=1.0, hi=0.5)
    with pytest.raises(ValueError, match="finite scalar"):
        ExpansionPoint(float("nan"))
    assert ExpansionPoint(None, default=0.25).fixed == 0.25
