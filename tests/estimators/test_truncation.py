"""Truncation distributions: survival tables and the per-lane sampling of N."""
import math

import numpy as np
import pytest

from styletrace.estimators import (
    Context,
    Cumulative,
    Geometric,
    Poisson,
    PoissonCMF,
    PowerLaw,
    resolve_truncation,
)

from .estimator_stats import Z, drjit_backend


def test_poisson_cmf_evaluates_until_the_cmf_reaches_the_threshold():
    t = PoissonCMF(2.0, 0.99)
    cmf = np.cumsum([math.exp(-2) * 2 ** k / math.factorial(k) for k in range(20)])
    assert t.deterministic == int(np.argmax(cmf >= 0.99)) == 6
    S = t.survival(12)
    assert np.all(S[:7] == 1.0)
    np.testing.assert_allclose(S[7:], np.cumprod([2.0 / k for k in range(7, 13)]), rtol=1e-14)


def test_poisson_survival_is_the_upper_tail():
    S = Poisson(2.5).survival(40)
    pk = [math.exp(-2.5 + k * math.log(2.5) - math.lgamma(k + 1)) for k in range(200)]
    want = [math.fsum(pk[k:]) for k in range(41)]
    np.testing.assert_allclose(S, want, rtol=1e-12)


def test_geometric_and_power_law_survival():
    np.testing.assert_allclose(Geometric(0.5, 2).survival(5), [1, 1, 1, 0.5, 0.25, 0.125])
    np.testing.assert_allclose(PowerLaw(2.0, 1).survival(4), [1, 1, 2 ** -2, 3 ** -2, 4 ** -2])


def test_tables_cap_where_a_float32_uniform_cannot_reach():
    K, S, invS, q, pmf = Geometric(0.5).tables(100)
    assert K == 24 and S[K] >= 2.0 ** -24  # 0.5^24 = 2^-24: the last reachable term
    assert pmf.sum() == pytest.approx(1.0, abs=1e-15) and q[K + 1] == 0.0
    np.testing.assert_allclose(invS * S, 1.0)
    assert Geometric(0.5).tables(10)[0] == 10  # max_terms caps first


@pytest.mark.parametrize("backend", ["numpy", "drjit"])
@pytest.mark.parametrize("trunc", [Poisson(2.0), PoissonCMF(1.5), Geometric(0.6, 1), PowerLaw(1.5)])
def test_sampled_counts_follow_the_distribution(backend, trunc):
    K, S, _, _, pmf = trunc.tables(30)
    lanes = 200_000
    u = np.random.default_rng(4).random(lanes)
    if backend == "numpy":
        ctx = Context("numpy", lanes=lanes)
        N = ctx.count_above(S, u.reshape(-1, 1))[:, 0]
    else:
        Float = drjit_backend().Float
        ctx = Context("drjit", like_t=Float)
        N = np.asarray(ctx.count_above(S, Float(u.astype(np.float32))))
    assert N.min() >= 0 and N.max() <= K and np.all(N == np.floor(N))
    freq = np.bincount(N.astype(int), minlength=K + 1) / lanes
    se = np.sqrt(pmf * (1 - pmf) / lanes) + 1.0 / lanes
    assert np.all(np.abs(freq - pmf) <= Z * se)


def test_names_and_invalid_parameters():
    assert isinstance(resolve_truncation("poisson_cmf"), PoissonCMF)
    assert isinstance(resolve_truncation("cumulative"), Cumulative)
    with pytest.raises(ValueError, match=r"unknown truncation 'poison'; allowed: .*'poisson_cmf'"):
        resolve_truncation("poison")
    with pytest.raises(ValueError, match="tau must be a positive finite number, got -1"):
        PoissonCMF(-1)
    with pytest.raises(ValueError, match="threshold must be < 1.0"):
        PoissonCMF(2.0, 1.0)
    with pytest.raises(ValueError, match="p must be < 1.0, got 1.5"):
        Geometric(1.5)
    with pytest.raises(ValueError, match="min_terms must be an integer >= 0"):
        PowerLaw(1.5, -1)
    with pytest.raises(ValueError, match="min_continue must be in"):
        Cumulative(2.0)
    with pytest.raises(ValueError, match="no fixed distribution"):
        Cumulative().survival(3)
