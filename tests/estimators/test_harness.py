"""The numpy/Dr.Jit harness and its test distributions."""
import numpy as np
import pytest

from styletrace.estimators import (
    Exponential,
    Mean,
    TwoPoint,
    Uniform,
    channel_means,
    estimate_numpy,
)


@pytest.mark.parametrize(
    "dist", [Uniform(0.2, 1.0), Exponential(0.3, 0.2), TwoPoint(0.25, 1.0, 0.3)]
)
def test_distribution_moments_match_their_quantile_function(dist):
    u = (np.arange(400_000) + 0.5) / 400_000
    x = dist.quantile(u)
    assert abs(x.mean() - dist.mean) < 1e-4 * max(1.0, dist.mean)
    # the exponential's midpoint grid misses the extreme tail: 1e-3 relative is its quadrature error
    assert abs(x.var() - dist.var) < 1e-3 * dist.var
    assert dist.moment(2) == pytest.approx(dist.var + dist.mean ** 2, rel=1e-3)


def test_estimate_numpy_counts_draws_and_uses_the_channel_convention():
    r = estimate_numpy(Mean(4), TwoPoint(0.0, 1.0, 0.5), 1000, np.random.default_rng(0), channels=3)
    assert np.all(r.draws == 4) and r.values.shape == (1000, 3)
    np.testing.assert_allclose(r.values[:, 1], 2 * r.values[:, 0])
    np.testing.assert_allclose(channel_means(Uniform(0, 1), 3), [0.5, 1.0, 1.5])
