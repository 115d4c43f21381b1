"""Expansion points from pilot samples: independent of the terms, counted, clamped."""
import numpy as np
import pytest

from styletrace.estimators import Pilot, PolynomialU, SeriesEstimator, gamma_series
from styletrace.estimators.pilot import ExpansionPoint

from .estimator_stats import DISTS, assert_unbiased, run_estimates


def test_pilot_samples_are_counted_and_separate():
    est = SeriesEstimator(gamma_series(2.2, lo=0.2, hi=1.0), b=Pilot(3))
    dist = DISTS["uniform"]
    r = run_estimates(est, dist, 100_000, seed=12)
    assert r.draws.min() >= 3 and est.mean_draws == pytest.approx(3 + np.sum(est.S[1:]))
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


def _pilot_b(pilot, xs):
    """b after feeding the pilot the draws xs (draws x lanes) on numpy lanes."""
    from styletrace.estimators.base import Context
    lanes = xs.shape[1]
    ctx = Context("numpy", lanes=lanes, dtype=np.float64, ndim=1)
    point = ExpansionPoint(pilot, series=gamma_series(2.2))
    state = point.start(ctx)
    for x in xs:
        # numpy lanes are (lanes, 1)
        state, _ = point.feed(ctx, state, x[:, None], np.ones((lanes, 1), bool))
    return np.asarray(point.value(ctx, state)).ravel()


def test_pilot_spread_aims_at_the_second_moment_ratio():
    """b = max(scale * mean, spread * mean(x^2) / mean(x)) over the pilot, against numpy on the
    same draws."""
    # heavy tailed: the ratio dominates
    xs = np.random.default_rng(4).exponential(1.0, (16, 64)) ** 3
    mean, ratio = xs.mean(0), (xs ** 2).mean(0) / xs.mean(0)
    np.testing.assert_allclose(
        _pilot_b(Pilot(16, scale=1.5, spread=1.0), xs), np.maximum(1.5 * mean, ratio)
    )
    np.testing.assert_allclose(_pilot_b(Pilot(16, scale=1.5), xs), 1.5 * mean)
    zeros = np.zeros((4, 3))  # a pilot of zeros keeps the mean rule (then the floor), no 0/0
    assert np.all(np.isfinite(_pilot_b(Pilot(4, lo=0.02, spread=1.0), zeros)))
    with pytest.raises(ValueError, match="pilot spread must be a finite number >= 0, got -1"):
        Pilot(1, spread=-1)


def test_pilot_spread_keeps_the_series_unbiased():
    est = SeriesEstimator(gamma_series(2.2), b=Pilot(4, spread=1.0))
    dist = DISTS["two-point"]
    r = run_estimates(est, dist, 100_000, seed=5)
    assert_unbiased(r.values, dist.mean ** (1 / 2.2))
