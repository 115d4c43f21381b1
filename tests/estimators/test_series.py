"""Power-series estimators (S9-S17, Eq. 24): unbiasedness for every selection and truncation."""
import numpy as np
import pytest

from styletrace.estimators import (
    Cumulative,
    Geometric,
    Pilot,
    Poisson,
    PoissonCMF,
    SeriesEstimator,
    Uniform,
    channel_means,
    exp_series,
    gamma_series,
    polynomial_series,
    power_series,
    reciprocal_series,
)

from .estimator_stats import BOUNDED, DISTS, Z, assert_unbiased, run_estimates

#: (selection, truncation, terms): every supported combination
PLANS = [
    ("iterative", PoissonCMF(2.0), "ustat"),
    ("iterative", PoissonCMF(2.0), "naive"),
    ("iterative", Geometric(0.6, 1), "ustat"),
    ("recursive", Cumulative(), "naive"),
    ("recursive", PoissonCMF(2.0), "naive"),
    ("single", Poisson(2.0), "naive"),
]
PLAN_IDS = [f"{s}-{t.name}-{m}" for s, t, m in PLANS]

TARGETS = {
    # series, expansion point, distributions (reciprocal/gamma on bounded ones: see estimator_stats)
    "exp": (exp_series(2.0), Pilot(1), DISTS),
    "exp-fixed-b": (exp_series(0.5), 0.5, DISTS),
    "reciprocal": (reciprocal_series(1.0, lo=0.2, hi=1.0), Pilot(1), BOUNDED),
    "gamma": (gamma_series(2.2, lo=0.2, hi=1.0), Pilot(2), BOUNDED),
}


def check_draws(r, est):
    """The measured draws per estimate agree with est.mean_draws (z-test on the count)."""
    if est.mean_draws is None:
        return
    d = r.draws.astype(float)
    se = max(d.std(ddof=1), 1e-12) / np.sqrt(len(d))
    assert abs(d.mean() - est.mean_draws) <= Z * se + 1e-12, (d.mean(), est.mean_draws)


@pytest.mark.parametrize("target", list(TARGETS))
@pytest.mark.parametrize("plan", PLANS, ids=PLAN_IDS)
def test_series_estimators_are_unbiased(target, plan):
    series, b, dists = TARGETS[target]
    selection, truncation, terms = plan
    est = SeriesEstimator(series, b=b, selection=selection, truncation=truncation, terms=terms)
    for i, (name, dist) in enumerate(dists.items()):
        r = run_estimates(est, dist, 100_000, seed=17 + i)
        assert_unbiased(r.values, series.function(dist.mean), what=f"{est.name} on {name}")
        check_draws(r, est)


@pytest.mark.parametrize("plan", PLANS, ids=PLAN_IDS)
def test_series_estimators_run_in_drjit_kernels(plan):
    selection, truncation, terms = plan
    series = gamma_series(2.2, lo=0.2, hi=3.0)
    est = SeriesEstimator(
        series, b=Pilot(1), selection=selection, truncation=truncation, terms=terms
    )
    dist = BOUNDED["uniform"]
    # Array3f, per-channel b
    r = run_estimates(est, dist, 100_000, backend="drjit", seed=5, channels=3)
    assert_unbiased(r.values, series.function(channel_means(dist, 3)), what=est.name)
    check_draws(r, est)


def test_fit_like_finite_series_with_pilot_center():
    poly = polynomial_series([0.2, -1.0, 0.0, 2.0, -0.5], center=1.0)
    # the pilot b hits the center 1.0, where the x^2 coefficient is exactly 0
    dist = DISTS["two-point"]
    for selection, truncation, terms in PLANS:
        if isinstance(truncation, Cumulative):
            # the documented remedy for interior zero coefficients
            truncation = Cumulative(min_continue=0.05)
        est = SeriesEstimator(
            poly, b=Pilot(1), selection=selection, truncation=truncation, terms=terms
        )
        r = run_estimates(est, dist, 100_000, seed=2)
        assert_unbiased(r.values, poly(dist.mean), what=est.name)
        assert np.all(r.draws <= 1 + 4)  # never beyond the degree


def test_cumulative_without_floor_stops_at_an_interior_zero_coefficient():
    # documented caveat: the running weight is 0 at a_2 = 0, so a_3 and a_4 are never reached
    poly = polynomial_series([0.2, -1.0, 0.0, 2.0, -0.5], center=1.0)
    est = SeriesEstimator(poly, b=1.0, selection="recursive", truncation=Cumulative())
    dist = DISTS["two-point"]
    r = run_estimates(est, dist, 100_000, seed=2)
    assert r.draws.max() == 2
    assert abs(r.mean - poly(dist.mean)) > Z * r.stderr


def test_the_cap_makes_it_unbiased_for_the_truncated_series():
    # max_terms = 2: E = a0 + a1 (I - b) + a2 (I - b)^2 exactly, not exp(I)
    series, b = exp_series(), 0.3
    est = SeriesEstimator(series, b=b, selection="recursive", truncation=Cumulative(), max_terms=2)
    dist = Uniform(0.0, 2.0)
    r = run_estimates(est, dist, 200_000, seed=8)
    a = series.coefficients(b, 2)
    truncated = a[0] + a[1] * (dist.mean - b) + a[2] * (dist.mean - b) ** 2
    assert_unbiased(r.values, truncated)
    assert abs(r.mean - series.function(dist.mean)) > Z * r.stderr  # and detectably not exp(I)


def test_integer_power_is_finite_and_exact_cost():
    est = SeriesEstimator(
        power_series(2.0), b=0.5, selection="iterative", truncation=PoissonCMF(2.0)
    )
    assert est.K == 2 and est.mean_draws == 2.0
    dist = DISTS["exponential"]
    r = run_estimates(est, dist, 100_000, seed=1)
    assert_unbiased(r.values, dist.mean ** 2)


def test_refusals_name_the_problem():
    s = reciprocal_series(1.0, lo=0.2, hi=1.0)
    with pytest.raises(ValueError, match="outside the convergence region"):
        SeriesEstimator(s, b=0.4)
    with pytest.raises(ValueError, match="terms='ustat' needs the number of terms"):
        SeriesEstimator(exp_series(), selection="recursive", terms="ustat")
    with pytest.raises(ValueError, match="only selection='recursive' can use it"):
        SeriesEstimator(exp_series(), selection="iterative", truncation=Cumulative())
    with pytest.raises(
        ValueError, match=r"single-term selection needs P\(k\) > 0.*k in \[0, 1, 2, 3, 4, 5\]"
    ):
        SeriesEstimator(exp_series(), selection="single", truncation=PoissonCMF(2.0))
    with pytest.raises(
        ValueError, match="unknown selection 'roulette'; allowed: single, iterative, recursive"
    ):
        SeriesEstimator(exp_series(), selection="roulette")
    with pytest.raises(ValueError, match="unknown truncation 'cmf'"):
        SeriesEstimator(exp_series(), truncation="cmf")
    with pytest.raises(ValueError, match="max_terms must be an integer >= 1, got 0"):
        SeriesEstimator(exp_series(), max_terms=0)
    with pytest.raises(ValueError, match="unknown term estimator"):
        SeriesEstimator(exp_series(), terms="exact")
    with pytest.raises(ValueError, match="expansion point b must be"):
        SeriesEstimator(exp_series(), b=[[1.0]])


@pytest.mark.parametrize("selection", ["iterative", "recursive", "single"])
def test_random_counts_are_drawn_per_lane_inside_the_kernel(selection):
    import styletrace.estimators as E
    """Inside one Dr.Jit loop each lane draws its own random number of samples (the renderer
    relies on this: no lane is replicated, lanes just loop longer or shorter), with the mean the
    estimator predicts."""
    est = E.SeriesEstimator(E.exp_series(), b=E.Pilot(1), selection=selection)
    r = E.estimate_drjit(est, E.Uniform(0.2, 1.0), 20000, seed=3)
    counts = r.draws.astype(np.float64)
    assert len(np.unique(counts)) > 3
    if est.mean_draws is not None:
        se = counts.std(ddof=1) / np.sqrt(len(counts))
        assert abs(counts.mean() - est.mean_draws) < 4 * se, (counts.mean(), est.mean_draws)


def test_scaled_terms_keep_float32_finite(jit):
    """With up to 64 terms (the expansion pass's series) the unscaled float32 kernel overflows:
    about b = 13, a_k = C(p, k) b^(p - k) underflows to 0 while (x - b)^k overflows, 0 x inf =
    NaN (measured: 5800 of 100000 estimates); the scaled one, (a_k b^k) x ((x - b) / b)^k, stays
    finite and is unbiased for the series truncated at 64 terms (its remainder is large here: b
    is 25x the mean). About b = 0.02 it is unbiased for g(I) itself. A per-lane b (PerLane) is a
    separate pass's: no pilot child among the draws."""
    from styletrace.estimators import PerLane
    from styletrace.estimators.harness import TwoPoint
    p, K = 1 / 2.2, 64
    firefly = TwoPoint(0.03, 20.0, 0.01)
    runs = {}
    for scaled in (False, True):
        est = SeriesEstimator(
            gamma_series(2.2),
            b=PerLane(jit.Float(13.0)),
            truncation=Geometric(0.9, 8),
            max_terms=K,
            scaled=scaled,
        )
        runs[scaled] = run_estimates(est, firefly, 100_000, backend="drjit", seed=3)
    assert not np.all(np.isfinite(runs[False].values))
    coeff = np.cumprod([1.0] + [(p - k) / (k + 1) for k in range(K)])  # C(p, k)
    truncated = 13.0 ** p * np.sum(coeff * (firefly.mean / 13.0 - 1.0) ** np.arange(K + 1))
    assert_unbiased(runs[True].values, truncated, what="scaled, b = 13")
    small = TwoPoint(0.005, 0.035, 0.5)
    est = SeriesEstimator(
        gamma_series(2.2),
        b=PerLane(jit.Float(0.02)),
        truncation=Geometric(0.9, 8),
        max_terms=K,
        scaled=True,
    )
    r = run_estimates(est, small, 100_000, backend="drjit", seed=4)
    assert_unbiased(r.values, small.mean ** p, what="scaled, b = 0.02")
    assert np.all(np.asarray(r.draws) >= 8)  # 8 terms always, no pilot child


def test_scaled_terms_need_ratio_series_and_ustat():
    with pytest.raises(ValueError, match="scaled=True needs selection='iterative', terms='ustat'"):
        SeriesEstimator(gamma_series(2.2), b=0.5, selection="recursive", scaled=True)
