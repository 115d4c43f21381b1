"""Theorem 4.1: sums (shared samples), products (independent groups), compositions."""
import numpy as np
import pytest

from styletrace.estimators import (
    Affine,
    Compose,
    Direct,
    Mean,
    Poisson,
    PolynomialNaive,
    PolynomialU,
    Product,
    SeriesEstimator,
    Sum,
    channel_means,
    exp_series,
    inner_mean,
)

from .estimator_stats import BACKENDS, DISTS, Z, assert_unbiased, run_estimates

SEPIA = np.array([[0.393, 0.769, 0.189], [0.349, 0.686, 0.168], [0.272, 0.534, 0.131]])


def cases():
    sq = PolynomialNaive([0.0, 0.0, 1.0])
    lin = Affine(3.0, 1.0)
    return {
        "sum-shared": (Sum(sq, lin), 2),
        "sum-unshared": (Sum(sq, lin, shared=False), 3),
        "product": (Product(lin, PolynomialU([0.0, 0.0, 1.0], n=3)), 4),
        "compose": (Compose(PolynomialU([0.0, 0.0, 1.0], n=3), Affine(2.0, 1.0)), 3),
        # shared sum of x^2 and a product of two affines
        "operators": (sq + lin * Affine(0.5, 0.0), 2),
    }


@pytest.mark.parametrize("name", list(cases()))
def test_algebra_is_unbiased_with_the_stated_cost(name):
    est, draws = cases()[name]
    assert est.mean_draws == draws
    for i, (dname, dist) in enumerate(DISTS.items()):
        r = run_estimates(est, dist, 100_000, seed=30 + i)
        assert_unbiased(r.values, est.exact(dist.mean), what=f"{est.name} on {dname}")
        assert np.all(r.draws == draws)


def test_exact_values_of_the_combinations():
    c = cases()
    I = 0.7
    assert c["sum-shared"][0].exact(I) == pytest.approx(I * I + 3 * I + 1)
    assert c["product"][0].exact(I) == pytest.approx((3 * I + 1) * I * I)
    assert c["compose"][0].exact(I) == pytest.approx((2 * I + 1) ** 2)


@pytest.mark.parametrize("backend", BACKENDS)
def test_composition_with_an_inner_estimator_that_sometimes_needs_no_draws(backend):
    # single-term series pick k = 0 with probability e^-2: that inner estimate needs no draw at all,
    # so the composition must produce it without waiting for one (a nested loop in the kernel)
    inner = SeriesEstimator(exp_series(), b=0.5, selection="single", truncation=Poisson(2.0))
    est = Compose(PolynomialU([0.0, 0.0, 1.0], n=2), inner)
    dist = DISTS["uniform"]
    r = run_estimates(est, dist, 200_000, backend=backend, seed=6)
    assert_unbiased(r.values, np.exp(dist.mean) ** 2, what=est.name)
    d = r.draws.astype(float)
    assert abs(d.mean() - est.mean_draws) <= Z * d.std() / np.sqrt(len(d))  # Wald: 2 x E[k] = 4
    assert (r.draws == 0).any()


@pytest.mark.parametrize("backend", BACKENDS)
def test_sepia_then_contrast_on_rgb(backend):
    # Fig. 10's combined estimator: contrast c (<I> - p) + p of a sepia matrix, then squared per
    # channel
    contrast = Affine(1.4, -0.4 * 0.5)
    est = Compose(PolynomialU([0.0, 0.0, 1.0], n=2), Compose(contrast, Affine(SEPIA)))
    dist = DISTS["two-point"]
    r = run_estimates(est, dist, 100_000, backend=backend, seed=2, channels=3)
    I = channel_means(dist, 3)
    assert_unbiased(r.values, (1.4 * (SEPIA @ I) - 0.2) ** 2, what=est.name)
    assert np.all(r.draws == 2)


def test_inner_means_with_and_without_comb():
    dist = DISTS["exponential"]
    for comb in (False, True):
        est = inner_mean(PolynomialU([0.0, 0.0, 0.0, 1.0], n=3), m=4, comb=comb)
        assert est.mean_draws == 12 and est.uses_comb == comb
        r = run_estimates(est, dist, 100_000, seed=4)
        assert_unbiased(r.values, dist.mean ** 3, what=est.name)
        assert np.all(r.draws == 12)


def test_comb_rules():
    with pytest.raises(ValueError, match="shared Sum cannot hold comb"):
        Sum(Mean(2, comb=True), Mean(2))
    with pytest.raises(ValueError, match="all or none"):
        Product(Mean(2, comb=True), Mean(2))
    with pytest.raises(ValueError, match="outer estimator of a composition"):
        Compose(Mean(2, comb=True), Mean(2))
    with pytest.raises(ValueError, match="Estimator instances"):
        Sum(Mean(1), 3.0)
    both = Product(Mean(2, comb=True), Direct(lambda x: x, 2, comb=True))
    r = run_estimates(both, DISTS["uniform"], 50_000, seed=1)
    assert_unbiased(r.values, DISTS["uniform"].mean ** 2)
