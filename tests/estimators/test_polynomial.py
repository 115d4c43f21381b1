"""Polynomial estimators: U-statistic recurrence exactness and stability, unbiasedness, variance."""
import itertools
import math

import numpy as np
import pytest

from styletrace.estimators import (
    Direct,
    Pilot,
    PolynomialNaive,
    PolynomialU,
    Uniform,
    polynomial_series,
    u_statistic_means,
)

from .estimator_stats import (
    BACKENDS,
    DISTS,
    Z,
    assert_detectably_biased,
    assert_unbiased,
    run_estimates,
    variance_and_se,
)


def brute_force_means(x, K):
    n = len(x)
    return [
        np.mean([np.prod([x[i] for i in c]) for c in itertools.combinations(range(n), k)])
        if k
        else 1.0
        for k in range(K + 1)
    ]


@pytest.mark.parametrize("n", [1, 2, 5, 7, 10])
def test_ustat_equals_brute_force_over_all_subsets(n):
    rng = np.random.default_rng(n)
    x = rng.normal(0.3, 1.0, size=n)  # signs mixed on purpose: cancellation must not matter
    got = u_statistic_means(x, n)
    want = brute_force_means(x, n)
    scale = max(1.0, max(abs(w) for w in want))
    np.testing.assert_allclose(got, want, rtol=1e-12, atol=1e-12 * scale)


def test_ustat_vectorized_over_lanes_matches_per_lane():
    rng = np.random.default_rng(3)
    x = rng.uniform(-1, 2, size=(8, 5))  # 8 samples, 5 lanes
    got = np.array(u_statistic_means(x, 6))
    for lane in range(5):
        np.testing.assert_allclose(
            got[:, lane], brute_force_means(x[:, lane], 6), rtol=1e-12, atol=1e-12
        )


def naive_symmetric_sums_float32(x, K):
    """The recurrence S7, s_k,n = s_k,n-1 + s_k-1,n-1 x_n, on raw sums: e_k grows like C(n, k)."""
    s = [np.float32(1.0)] + [np.float32(0.0)] * K
    for xi in x:
        for k in range(K, 0, -1):
            s[k] = np.float32(s[k] + s[k - 1] * xi)
    return s


def test_ustat_float32_is_accurate_for_n4096_k20_where_naive_forms_fail():
    n, K = 4096, 20
    rng = np.random.default_rng(20)
    x64 = rng.uniform(0.5, 1.5, size=n)
    x32 = x64.astype(np.float32)
    with np.errstate(over="ignore", invalid="ignore"):
        # same inputs, float64 arithmetic
        ref = np.array(u_statistic_means(x32.astype(np.float64), K))
        got = np.array(u_statistic_means(x32, K))
        assert got.dtype == np.float32
        # Tolerance: for positive samples every update m_k + (k/j)(y m_(k-1) - m_k) equals a
        # weighted average of positive numbers and costs at most 5 roundings (k/j, product,
        # difference, scaling, sum), so the relative error grows by at most ~8 u per sample (u =
        # 2^-24, doubled for the difference's cancellation) and is not amplified: |rel err| <= 8 n u
        # = 1.95e-3. The float64 reference's own error is ~8 n 2^-53, negligible.
        tol = 8 * n * 2.0 ** -24
        rel = np.abs(got - ref) / np.abs(ref)
        assert np.all(rel <= tol), f"max relative error {rel.max():.2e} > {tol:.2e}"
        assert rel.max() < tol / 10  # in practice errors random-walk: far below the worst case

        # naive 1: elementary symmetric sums (S7) in float32, then divide by the binomial
        # coefficient
        s = naive_symmetric_sums_float32(x32, K)
        assert not np.isfinite(s[K])  # e_20 ~ C(4096, 20) ~ 8e53 overflows float32 (max 3.4e38)
        assert not np.isfinite(np.float32(s[K]) / np.float32(math.comb(n, K)))  # inf / inf = nan
        # naive 2: the binomial form in float32: C(4096, 20) itself is not representable
        assert not np.isfinite(np.float32(math.comb(n, K)))
        # and it is not only the top order: e_k ~ C(n, k) passes 3.4e38 from k = 14 on, so every
        # term of a polynomial above degree 13 is lost, while the running means stay O(1)
        finite = [k for k in range(K + 1) if np.isfinite(s[k])]
        assert max(finite) == 13 and np.all(np.isfinite(got))


@pytest.mark.parametrize("dist_name", list(DISTS))
@pytest.mark.parametrize("k", [2, 3, 5])
def test_naive_and_ustat_are_unbiased_for_powers(dist_name, k):
    dist = DISTS[dist_name]
    coeffs = [0.0] * k + [1.0]
    for est in (PolynomialNaive(coeffs), PolynomialU(coeffs, n=k + 3)):
        r = run_estimates(est, dist, 100_000, seed=10 * k)
        assert np.all(r.draws == est.mean_draws)
        assert_unbiased(r.values, dist.mean ** k, what=f"{est.name} on {dist_name}")


@pytest.mark.parametrize("backend", BACKENDS)
def test_multiterm_polynomial_about_a_pilot_point_is_unbiased(backend):
    dist = DISTS["uniform"]
    poly = polynomial_series([0.3, -1.0, 2.0, 0.5], center=0.2)
    for est in (
        PolynomialNaive(poly, b=Pilot(2)),
        PolynomialU(poly, n=6, b=Pilot(1)),
        PolynomialU(poly, n=4, b=0.7),
    ):
        r = run_estimates(est, dist, 200_000, backend=backend, seed=5)
        assert_unbiased(r.values, poly(dist.mean), what=est.name)
        assert np.all(r.draws == est.mean_draws)


def test_unbiasedness_check_can_fail_on_the_direct_estimator():
    # the same check, the same budget, a biased estimator: E[<I>_2^3] - I^3 = 3 I Var / 2 +
    # E[(x-I)^3] / 4
    dist = Uniform(0.0, 1.0)
    r = run_estimates(Direct(lambda x: x ** 3, 2), dist, 100_000, seed=1)
    assert_detectably_biased(r.values, dist.mean ** 3, what="direct x^3")


@pytest.mark.parametrize("k,n", [(2, 4), (2, 8), (3, 6)])
def test_ustat_variance_is_at_most_naive_at_equal_sample_count(k, n):
    """U-statistic over n samples vs the mean of n/k independent naive products (also n samples)."""
    dist = DISTS["exponential"]
    runs = 200_000
    coeffs = [0.0] * k + [1.0]
    u = run_estimates(PolynomialU(coeffs, n=n), dist, runs, seed=1).values
    groups = [
        run_estimates(PolynomialNaive(coeffs), dist, runs, seed=100 + g).values
        for g in range(n // k)
    ]
    naive = np.mean(groups, axis=0)
    vu, su = variance_and_se(u)
    vn, sn = variance_and_se(naive)
    # analytic variances (Hoeffding): Var U = sum_c C(k,c) C(n-k,k-c) / C(n,k) zeta_c,
    # zeta_c = Var E[x1..xk | x1..xc] = mu^(2(k-c)) E[x^2]^c - mu^(2k); naive: zeta_k / (n/k)
    mu, m2 = dist.mean, dist.var + dist.mean ** 2
    zeta = [mu ** (2 * (k - c)) * m2 ** c - mu ** (2 * k) for c in range(k + 1)]
    var_u = sum(
        math.comb(k, c) * math.comb(n - k, k - c) * zeta[c] for c in range(1, k + 1)
    ) / math.comb(n, k)
    var_n = zeta[k] / (n // k)
    assert abs(vu - var_u) <= Z * su and abs(vn - var_n) <= Z * sn
    assert vn - vu > Z * math.hypot(su, sn), f"U {vu:.4g} not below naive {vn:.4g}"


def test_equal_variance_when_n_equals_k():
    # with n = k the U-statistic has one subset: it is the naive product (a sanity check of the test
    # above)
    assert PolynomialU([0, 0, 1], n=2).mean_draws == PolynomialNaive([0, 0, 1]).mean_draws


def test_invalid_parameters_are_refused_with_the_bad_value():
    with pytest.raises(ValueError, match="n >= 3"):
        PolynomialU([0, 0, 0, 1], n=2)
    with pytest.raises(ValueError, match="n must be an integer >= 1, got -1"):
        PolynomialU([0, 1], n=-1)
    with pytest.raises(ValueError, match="shape"):
        PolynomialNaive(np.zeros((2, 2, 2)))
    with pytest.raises(ValueError, match="at least K samples"):
        u_statistic_means(np.ones(3), 4)
