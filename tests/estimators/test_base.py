"""The kernel contract: run(draw, carry, uniform, active, like) on numpy and inside Dr.Jit loops."""
import numpy as np
import pytest

from styletrace.estimators import (
    Cumulative,
    Mean,
    Pilot,
    PolynomialU,
    SeriesEstimator,
    Uniform,
    channel_means,
    estimate_drjit,
    estimate_numpy,
    gamma_series,
)

from .estimator_stats import (
    DISTS,
    Z,
    assert_unbiased,
    drjit_backend,
    run_estimates,
    variance_and_se,
)


def hash_uniform(seed, index):
    """A per-lane uniform from (seed, draw index): a stateless stand-in for a sampler."""
    jit = drjit_backend()
    Float, UInt32 = jit.Float, jit.UInt32
    h = seed * UInt32(747796405) + index * UInt32(2891336453) + UInt32(12345)
    for _ in range(3):
        h = h ^ (h >> 16)
        h = h * UInt32(0x45D9F3B)
    return Float(h >> 8) * (1.0 / (1 << 24))


def mean_of_n_in_drjit(n, thread_carry=True, lanes=100_000):
    jit = drjit_backend()  # first: it loads Dr.Jit with a working libLLVM
    import drjit as dr
    Float, UInt32 = jit.Float, jit.UInt32
    calls = []

    def draw(carry):
        seed, index = carry
        calls.append(dr.flag(dr.JitFlag.SymbolicScope))
        x = hash_uniform(seed, index)
        # the classic bug: not handing back the advanced carry reuses the same random number
        return x, ((seed, index + 1) if thread_carry else carry)

    def uniform(carry):
        seed, index = carry
        return hash_uniform(seed + UInt32(99991), index), (seed, index + 1)

    carry = (dr.arange(UInt32, lanes), dr.zeros(UInt32, lanes))
    value, _ = Mean(n).run(draw, carry, uniform, like=Float)
    assert calls and all(calls)  # traced once, inside the symbolic loop body only
    return np.asarray(value, dtype=np.float64)


def test_variance_of_the_mean_of_n_draws_falls_as_one_over_n_in_drjit():
    var = 1.0 / 12.0
    for n in (1, 4, 16):
        v, se = variance_and_se(mean_of_n_in_drjit(n))
        assert abs(v - var / n) <= Z * se, (n, v)


def test_the_one_over_n_check_catches_a_carry_that_is_not_threaded():
    v, se = variance_and_se(mean_of_n_in_drjit(16, thread_carry=False))
    assert abs(v - 1.0 / 12.0 / 16) > Z * se and abs(v - 1.0 / 12.0) <= Z * se


def test_drjit_and_numpy_agree_on_mean_and_variance():
    est = SeriesEstimator(gamma_series(2.2, lo=0.2, hi=1.0), b=Pilot(1), selection="recursive",
                          truncation=Cumulative())
    dist = DISTS["uniform"]
    a = run_estimates(est, dist, 200_000, backend="numpy", seed=1).values
    b = run_estimates(est, dist, 200_000, backend="drjit", seed=1).values
    assert_unbiased(a, dist.mean ** (1 / 2.2))
    assert_unbiased(b, dist.mean ** (1 / 2.2))
    (va, sa), (vb, sb) = variance_and_se(a), variance_and_se(b)
    assert abs(va - vb) <= Z * np.hypot(sa, sb)
    assert abs(a.mean() - b.mean()) <= Z * np.hypot(
        a.std() / np.sqrt(len(a)), b.std() / np.sqrt(len(b))
    )


@pytest.mark.parametrize("backend", ["numpy", "drjit"])
def test_inactive_lanes_draw_nothing_and_return_zero(backend):
    lanes = 3000
    active = np.arange(lanes) % 3 != 0
    est = PolynomialU([0.0, 1.0, 1.0], n=3)
    if backend == "numpy":
        r = estimate_numpy(
            est, DISTS["uniform"], lanes, np.random.default_rng(0), channels=3, active=active
        )
    else:
        r = estimate_drjit(
            est, DISTS["uniform"], lanes, channels=3, active=drjit_backend().Bool(active)
        )
    assert np.all(r.values[~active] == 0.0) and np.all(r.draws[~active] == 0)
    assert np.all(r.draws[active] == 3) and np.all(r.values[active] != 0.0)


@pytest.mark.parametrize("dtype", [np.float32, np.float64])
@pytest.mark.parametrize("channels", [None, 3])
def test_numpy_values_keep_the_shape_and_dtype_of_the_samples(dtype, channels):
    r = estimate_numpy(
        PolynomialU([0.5, 1.0, 1.0], n=2),
        DISTS["two-point"],
        50_000,
        np.random.default_rng(1),
        channels=channels,
        dtype=dtype,
    )
    assert r.values.dtype == dtype and r.values.shape == (
        (50_000,) if channels is None else (50_000, channels)
    )
    I = channel_means(DISTS["two-point"], channels)
    assert_unbiased(r.values, 0.5 + I + I * I)


def test_numpy_run_without_like_or_active_learns_the_lanes_from_uniform():
    rng = np.random.default_rng(2)

    def draw(carry):
        n = carry["n"].shape[0]
        return rng.random(n), {"n": carry["n"] + 1}

    def uniform(carry):
        return rng.random(carry["n"].shape[0]), carry

    value, carry = Mean(3).run(draw, {"n": np.zeros(500, int)}, uniform)
    assert value.shape == (500,) and np.all(carry["n"] == 3)


def test_drjit_needs_like_and_checks_the_type(jit):
    import drjit as dr
    Array3f, Bool, Float = jit.Array3f, jit.Bool, jit.Float
    with pytest.raises(ValueError, match="needs like="):
        Mean(1).run(lambda c: (Float(1.0), c), (), lambda c: (Float(0.5), c), active=Bool(True))
    # Dr.Jit re-raises errors from a loop body
    with pytest.raises((ValueError, RuntimeError)) as err:
        Mean(1).run(lambda c: (np.ones(3), c), (), lambda c: (Float(0.5), c), like=Array3f)
    chain = [err.value, err.value.__cause__, err.value.__context__]
    assert any("draw() returned ndarray; like=Array3f" in str(e) for e in chain if e is not None)
    with pytest.raises(ValueError, match="like must be the type"):
        Mean(1).run(
            lambda c: (Float(1.0), c), (), lambda c: (Float(0.5), c), Bool(True), like="Color3f"
        )
    with pytest.raises(TypeError):  # like is keyword-only: a fifth positional argument is a mistake
        Mean(1).run(lambda c: (Float(1.0), c), (), lambda c: (Float(0.5), c), Bool(True), Float)
    v, _ = Mean(2).run(lambda c: (Array3f(1, 2, 3), c), (), lambda c: (Float(0.5), c), like=Array3f)
    assert isinstance(v, Array3f) and np.allclose(np.asarray(v).ravel(), [1, 2, 3])
    assert dr.width(v) == 1


def mitsuba_with_variant():
    """Mitsuba with the variant styletrace.init() chose (cuda_ad_rgb where CUDA works, else
    llvm_ad_rgb, or the one set before): the tests follow the backend instead of naming one."""
    import importlib.util
    if importlib.util.find_spec("mitsuba") is None:
        pytest.skip("Mitsuba is not installed")
    import styletrace
    # before `import mitsuba`: it loads Dr.Jit, which needs a working libLLVM
    variant = styletrace.init()
    import mitsuba as mi
    assert mi.variant() == variant
    return mi


def test_mitsuba_color3f_values():
    mi = mitsuba_with_variant()
    if not hasattr(mi, "Color3f"):
        pytest.skip("scalar Mitsuba variant")
    dist = Uniform(0.2, 1.0)
    est = PolynomialU([0.0, 0.0, 1.0], n=3, b=Pilot(1))
    r = estimate_drjit(est, dist, 100_000, like=mi.Color3f, channels=3)
    assert_unbiased(r.values, channel_means(dist, 3) ** 2, what="Color3f")


def test_a_mitsuba_sampler_in_the_carry_advances_every_iteration():
    """The integrator's set-up: carry = (sampler,), draw returns mi.Color3f, uniform uses the
    sampler."""
    mi = mitsuba_with_variant()
    if not hasattr(mi, "Color3f") or mi.variant().startswith("scalar"):
        pytest.skip("needs a JIT Mitsuba variant")
    import drjit as dr
    lanes = 100_000
    sampler = mi.load_dict({"type": "independent"})
    sampler.seed(7, lanes)

    def draw(carry):
        (s,) = carry
        u = s.next_1d()
        return mi.Color3f(u, 2.0 * u, 0.5), (s,)

    def uniform(carry):
        (s,) = carry
        return s.next_1d(), (s,)

    for m in (1, 16):
        value, _ = Mean(m).run(draw, (sampler,), uniform, mi.Bool(True), like=mi.Color3f)
        v = np.asarray(value, dtype=np.float64).T
        var, se = variance_and_se(v[:, 0])
        assert abs(var - 1.0 / 12.0 / m) <= Z * se
    est = SeriesEstimator(gamma_series(2.2, lo=0.0, hi=3.0), b=Pilot(2))
    value, _ = est.run(draw, (sampler,), uniform, mi.Bool(True), like=mi.Color3f)
    dr.eval(value)
    assert_unbiased(np.asarray(value, dtype=np.float64).T, np.array([0.5, 1.0, 0.5]) ** (1 / 2.2))
