"""Affine estimators (S1-S3): scalar, per-channel, channel-mixing matrix; the comb-stratified
mean."""
import numpy as np
import pytest

from styletrace.estimators import Affine, Mean, TwoPoint, Uniform, channel_means

from .estimator_stats import BACKENDS, DISTS, Z, assert_unbiased, run_estimates, variance_and_se

SEPIA = np.array([[0.393, 0.769, 0.189], [0.349, 0.686, 0.168], [0.272, 0.534, 0.131]])


@pytest.mark.parametrize("backend", BACKENDS)
@pytest.mark.parametrize("a1,a0", [(2.0, 1.0), ([0.5, -1.0, 2.0], [0.0, 0.1, 0.2]), (SEPIA, 0.05)])
def test_affine_is_unbiased(backend, a1, a0):
    est = Affine(a1, a0, n=2)
    for i, (name, dist) in enumerate(DISTS.items()):
        r = run_estimates(est, dist, 50_000, backend=backend, seed=i, channels=3)
        I = channel_means(dist, 3)
        assert_unbiased(r.values, est.exact(I), what=f"{est.name} {name}")
        np.testing.assert_allclose(
            est.exact(I), np.asarray(a1) @ I + a0 if np.ndim(a1) == 2 else np.asarray(a1) * I + a0
        )
        assert np.all(r.draws == 2)


@pytest.mark.parametrize("backend", BACKENDS)
def test_mean_variance_falls_as_one_over_m_and_comb_as_one_over_m_squared(backend):
    # on Dr.Jit the carry is a PCG32: a sampler left out of the loop state would repeat its numbers
    # and the variance would not fall
    dist = Uniform(0.0, 1.0)
    for m in (1, 4, 16):
        v, se = variance_and_se(
            run_estimates(Mean(m), dist, 100_000, backend=backend, seed=m).values
        )
        assert abs(v - dist.var / m) <= Z * se
        vc, sec = variance_and_se(
            run_estimates(Mean(m, comb=True), dist, 100_000, backend=backend, seed=m).values
        )
        # linear quantile: the comb mean is xi/m + const
        assert abs(vc - dist.var / m ** 2) <= Z * sec


def test_comb_keeps_the_mean_unbiased_on_a_discrete_distribution():
    dist = TwoPoint(0.0, 1.0, 0.37)
    r = run_estimates(Mean(5, comb=True), dist, 100_000, seed=2)
    assert_unbiased(r.values, dist.mean)
    # a comb of 5 over P(1) = 0.37 gives 1 or 2 ones: variance (0.85 * 0.15) / 25 vs iid 0.37 * 0.63
    # / 5
    v, se = variance_and_se(r.values)
    assert abs(v - 0.85 * 0.15 / 25) <= Z * se


def test_invalid_parameters():
    with pytest.raises(ValueError, match="square matrix"):
        Affine(np.ones((2, 3)))
    with pytest.raises(ValueError, match="n must be an integer >= 1, got 0"):
        Affine(1.0, n=0)
    with pytest.raises(ValueError, match="finite"):
        Affine(np.nan)
    with pytest.raises(ValueError, match="3 channels"):
        Affine(SEPIA).exact(np.ones(2))
