"""Truth of the direct estimator on a scene whose first-hit radiance is known exactly.

A diffuse sphere of albedo rho under a constant environment E has exitant radiance I = rho*E at
every point (it is convex: each point sees only the environment). Each inner sample X is one
path-traced estimate of I; by symmetry every visible point of the sphere has the same distribution
of X, so the pixels inside the sphere's silhouette are independent draws, which gives standard
errors directly.
"""
import numpy as np
import pytest
from helpers.furnace import I, draws

import styletrace
from styletrace.gate import mi

RES = 128
GAMMA = 2.2
Z = 4.0


@pytest.fixture(scope="module")
def single(scene, mask):
    """Draws of X (identity style, one inner sample): the distribution every estimator sees."""
    return draws(scene, mask, "identity", 1, 24, 0).astype(np.float64)


def test_identity_is_exact(single):
    se = single.std(0, ddof=1) / np.sqrt(len(single))
    z = (single.mean(0) - I) / se
    assert np.all(np.abs(z) < Z), f"mean {single.mean(0)} vs exact {I}: z = {z}"


@pytest.mark.parametrize(
    "sampler", ["independent", "stratified", "multijitter", "orthogonal", "ldsampler", "owen_sobol"]
)
def test_inner_samples_are_independent(mask, sampler):
    """Var(<I>_n) = Var(<I>_1)/n whatever the scene's sampler: catches inner loops that replay
    the same random numbers (a sampler outside the loop state, or one whose dimension counter is
    a trace-time constant, as ldsampler's) or correlate them (orthogonal). 4 samples per pixel: a
    size every one of these samplers accepts as it is."""
    n = 8
    d = styletrace.frontends.api.scene_dict("furnace", RES, RES)
    d["sensor"]["sampler"] = {"type": sampler, "sample_count": 4}
    scene = mi.load_dict(d)
    ones = draws(scene, mask, "identity", 1, 12, 0)
    means = draws(scene, mask, "identity", n, 12, 1000)
    v1, vn = ones.var(0, ddof=1), means.var(0, ddof=1)
    # standard errors of the sample variances from the fourth central moments
    se1 = np.sqrt((((ones - ones.mean(0)) ** 4).mean(0) - v1 ** 2) / len(ones))
    sen = np.sqrt((((means - means.mean(0)) ** 4).mean(0) - vn ** 2) / len(means))
    z = (n * vn - v1) / np.sqrt((n * sen) ** 2 + se1 ** 2)
    assert np.all(np.abs(z) < Z), f"n*Var(<I>_n) = {n * vn} vs Var(<I>_1) = {v1}: z = {z}"


def gamma(x):
    return np.maximum(x, 0.0) ** (1.0 / GAMMA)


@pytest.mark.parametrize("n", [1, 2, 4, 8, 16])
def test_direct_bias_follows_delta_method(scene, mask, single, n):
    """E[g(<I>_n)] - g(I): matches the resampled truth for every n and g''(I) Var/(2n) for n >= 4.

    The resampled truth averages g over means of n draws of X taken from an independent pool, so it
    includes every order of the bias; the delta method keeps the 1/n term only, which dominates once
    n >= 4 here (the 1/n^2 term is below a tenth of the standard error).
    """
    vals = draws(scene, mask, "gamma", n, 12 * n, 10_000 * n, exposure=1.0).astype(np.float64)
    bias = vals.mean(0) - gamma(I)
    se = vals.std(0, ddof=1) / np.sqrt(len(vals))

    rng = np.random.default_rng(7)
    pool = single[rng.integers(0, len(single), (400_000, n))].mean(1)
    g_pool = gamma(pool)
    resampled = g_pool.mean(0) - gamma(I)
    se_pool = g_pool.std(0, ddof=1) / np.sqrt(len(g_pool))
    # the pool's own mean differs from I by sampling error; carry it into the truth's uncertainty
    se_pool = np.sqrt(
        se_pool**2 + (gamma(I) / GAMMA / I * single.std(0) / np.sqrt(len(single))) ** 2
    )
    z = (bias - resampled) / np.sqrt(se ** 2 + se_pool ** 2)
    assert np.all(np.abs(z) < Z), f"n={n}: bias {bias} vs resampled {resampled}: z = {z}"

    g2 = (1 / GAMMA) * (1 / GAMMA - 1) * I ** (1 / GAMMA - 2)
    delta = g2 * single.var(0, ddof=1) / (2 * n)
    if n == 1:
        assert np.all(bias / se < -Z), (
            f"direct application with n=1 should be measurably biased: z = {bias / se}"
        )
    if n >= 4:
        zd = (bias - delta) / se
        assert np.all(np.abs(zd) < Z), f"n={n}: bias {bias} vs delta method {delta}: z = {zd}"
