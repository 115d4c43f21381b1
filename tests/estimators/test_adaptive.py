"""Direct application with adaptive stopping (estimators/adaptive.py): where it stops, what it
reports, and that at the same mean number of children it beats a fixed count on a step function."""
import numpy as np
import pytest

from styletrace.estimators import AdaptiveDirect, Direct, channel_mean

from .estimator_stats import Z


def lanes_with_means(mu, half_width, seed):
    """draw/uniform over lanes whose samples are U(mu - w, mu + w), mu per lane (numpy,
    lane-compacting)."""
    rng = np.random.default_rng(seed)

    def draw(carry):
        (idx,) = carry
        return mu[idx] + rng.uniform(-half_width, half_width, size=idx.shape), (idx,)

    def uniform(carry):
        (idx,) = carry
        return rng.uniform(size=idx.shape), (idx,)
    return draw, uniform, (np.arange(len(mu)),)


def step(x):
    return (x > 0.5) * 1.0


def test_stops_at_n0_far_from_the_threshold_and_goes_to_n_max_at_it():
    # samples within 0.1 of mu: at n0 = 4, s <= 0.1 sqrt(4/3) and the band t s / sqrt(n) <= 3.17 *
    # 0.058 = 0.183, while a mean of a lane at mu = 0.05 or 0.95 is at least 0.35 from the
    # threshold: never past n0
    mu = np.repeat([0.05, 0.95, 0.5], 2000)
    est = AdaptiveDirect(step, 4, 64, thresholds=(0.5,), z=2.0)
    draw, uniform, carry = lanes_with_means(mu, 0.1, seed=1)
    est.run(draw, carry, uniform, like=np.zeros(len(mu)))
    n = est.stats["children"][:, 0]
    assert np.all(n[:4000] == 4)
    # at the threshold the mean stays within z standard errors of it with probability about 0.95 at
    # every step, so most lanes draw all 64; those that stop early left the band (checked from the
    # stats)
    at = n[4000:]
    assert np.all((at >= 4) & (at <= 64)) and np.mean(at == 64) > 0.5


def test_the_stop_rule_holds_where_each_lane_stopped():
    # replay: a lane that stopped before n_max has its mean outside the band, one at n_max may be
    # inside (the band in standard errors is Student's t quantile for z = 2, at least 2)
    rng = np.random.default_rng(2)
    mu = rng.uniform(0.0, 1.0, 5000)
    est = AdaptiveDirect(lambda x: x, 4, 32, thresholds=(0.5,), z=2.0)
    draw, uniform, carry = lanes_with_means(mu, 0.5, seed=3)
    # g = identity: value is the mean
    value, _ = est.run(draw, carry, uniform, like=np.zeros(len(mu)))
    n, var = est.stats["children"][:, 0], est.stats["variance"][:, 0]
    inside = np.abs(value - 0.5) < est.band_width(n) * np.sqrt(var / n)
    assert not np.any(inside & (n < 32))
    assert np.any(inside & (n == 32)) and np.any(n == 4) and np.any((n > 4) & (n < 32))


def test_smooth_rule_draws_until_the_predicted_bias_is_below_target():
    # g = x^2 has g'' = 2: predicted bias 2 s^2 / (2n) = s^2 / n, the exact bias of direct
    # application
    mu = np.full(4000, 0.5)
    target = (1.0 / 12.0) / 20  # U(0, 1): Var = 1/12, so about 20 children
    est = AdaptiveDirect(lambda x: x * x, 4, 64, curvature=lambda m, h: 2.0 + 0.0 * m, bias=target)
    draw, uniform, carry = lanes_with_means(mu, 0.5, seed=4)
    est.run(draw, carry, uniform, like=np.zeros(len(mu)))
    n, var, bias = (est.stats[k][:, 0] for k in ("children", "variance", "bias"))
    np.testing.assert_allclose(bias, var / n, rtol=1e-12)
    assert np.all(bias[n < 64] <= target)
    assert 10 < n.mean() < 40 and np.all(n >= 4)
    # a linear g has no curvature: it never draws past n0
    flat = AdaptiveDirect(lambda x: x, 4, 64, curvature=lambda m, h: 0.0 * m, bias=target)
    draw, uniform, carry = lanes_with_means(mu, 0.5, seed=4)
    flat.run(draw, carry, uniform, like=np.zeros(len(mu)))
    assert np.all(flat.stats["children"] == 4) and np.all(flat.stats["bias"] == 0)


def test_a_fixed_count_is_direct_application_bit_for_bit():
    mu = np.linspace(0.0, 1.0, 1000)
    est = AdaptiveDirect(np.exp, 8, 8, thresholds=(0.5,))
    draw, uniform, carry = lanes_with_means(mu, 0.3, seed=5)
    a, _ = est.run(draw, carry, uniform, like=np.zeros(1000))
    draw, uniform, carry = lanes_with_means(mu, 0.3, seed=5)
    b, _ = Direct(np.exp, 8).run(draw, carry, uniform, like=np.zeros(1000))
    assert np.array_equal(a, b) and np.all(est.stats["children"] == 8)


def test_adaptive_beats_a_fixed_count_with_the_same_mean_children_on_a_step():
    # means spread over [0, 1] around one threshold; the reference is the exact g(mu) (brute force
    # would converge to it). Paired per-lane squared errors give the MSE difference and its standard
    # error.
    lanes = 40_000
    mu = np.random.default_rng(6).uniform(0.0, 1.0, lanes)
    est = AdaptiveDirect(step, 4, 64, thresholds=(0.5,))
    draw, uniform, carry = lanes_with_means(mu, 0.5, seed=7)
    va, _ = est.run(draw, carry, uniform, like=np.zeros(lanes))
    n_fixed = int(round(est.stats["children"].mean()))
    draw, uniform, carry = lanes_with_means(mu, 0.5, seed=8)
    vf, _ = Direct(step, n_fixed).run(draw, carry, uniform, like=np.zeros(lanes))
    exact = step(mu)
    ea, ef = (va - exact) ** 2, (vf - exact) ** 2
    diff = ef - ea
    se = diff.std(ddof=1) / np.sqrt(lanes)
    assert 4 < n_fixed < 64
    assert diff.mean() > Z * se, (ea.mean(), ef.mean(), n_fixed)


def test_on_drjit_arrays(jit):
    # the same rule inside a Dr.Jit loop on Array3f samples; per-lane thresholds as a Float
    lanes = 4096
    rng = jit.PCG32(lanes)
    far = jit.Float(np.repeat([0.05, 0.5], lanes // 2))

    def draw(carry):
        (r,) = carry
        u = r.next_float32()
        x = far + (u - 0.5) * 0.2  # within 0.1 of the lane's mean, as above
        return jit.Array3f(x, x, x), (r,)

    def uniform(carry):
        (r,) = carry
        return r.next_float32(), (r,)
    est = AdaptiveDirect(lambda x: x, 4, 64, thresholds=(jit.Float(0.5),))
    value, _ = est.run(draw, (rng,), uniform, like=jit.Array3f)
    n = np.array(est.stats["children"])
    assert np.all(n[: lanes // 2] == 4) and np.mean(n[lanes // 2:] == 64) > 0.5
    assert np.allclose(np.array(channel_mean(value)), np.array(value[0]))


def t_quantile(p, v):
    """Student's t quantile by bisection on its CDF, the density integrated numerically
    (Simpson)."""
    import math
    c = math.gamma((v + 1) / 2) / (math.sqrt(v * math.pi) * math.gamma(v / 2))

    def cdf(x):
        t = np.linspace(0.0, x, 20001)
        f = c * (1 + t * t / v) ** (-(v + 1) / 2)
        return 0.5 + (t[1] - t[0]) / 3 * (f[0] + f[-1] + 4 * f[1:-1:2].sum() + 2 * f[2:-1:2].sum())
    lo, hi = 0.0, 50.0
    for _ in range(60):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if cdf(mid) < p else (lo, mid)
    return lo


def test_the_band_is_students_t_for_few_children():
    # an asymptotic expansion whose terms shrink: its error is below the last term it keeps,
    # (79z^9 + 776z^7 + 1482z^5 - 1920z^3 - 945z) / (92160 v^4)
    import math
    z = 2.0
    est = AdaptiveDirect(step, 4, 64, z=z)
    for n in (4, 8, 16, 64):
        v = n - 1
        exact = t_quantile(0.5 * (1 + math.erf(z / math.sqrt(2))), v)
        next_term = (79 * z**9 + 776 * z**7 + 1482 * z**5 - 1920 * z**3 - 945 * z) / (92160 * v**4)
        assert abs(est.band_width(float(n)) - exact) <= next_term, (
            n,
            est.band_width(float(n)),
            exact,
        )
    assert est.band_width(1e6) == pytest.approx(z, rel=1e-5)


def test_invalid_parameters():
    with pytest.raises(ValueError, match="n_max must be an integer >= 8, got 4"):
        AdaptiveDirect(np.exp, 8, 4)
    with pytest.raises(ValueError, match="z and bias must be positive"):
        AdaptiveDirect(np.exp, 4, 8, z=0.0)
    with pytest.raises(ValueError, match="curvature must be None or a callable"):
        AdaptiveDirect(np.exp, 4, 8, curvature=2.0)
