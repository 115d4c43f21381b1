"""Statistics shared by the estimator tests: z-tests whose tolerances come from the data.

Every check of an expectation is a z-test: |mean - exact| <= Z * stderr, with stderr the sample
standard deviation over sqrt(runs). With Z = 4 a correct estimator fails with probability ~6e-5
per check (normal approximation; the seeds are fixed, so the suite is deterministic). The
"can fail" checks assert the opposite (a wrong estimator is more than Z standard errors off).
"""
import numpy as np

#: The test distributions of I (all with known mean): bounded, heavy-ish tailed, discrete.
from styletrace.estimators import Exponential, TwoPoint, Uniform

Z = 4.0

DISTS = {
    "uniform": Uniform(0.2, 1.0),
    "exponential": Exponential(scale=0.3, shift=0.2),
    "two-point": TwoPoint(0.25, 1.0, 0.3),
}
#: Bounded ones, for series whose terms (x - b)^k have unbounded variance on unbounded samples.
BOUNDED = {k: v for k, v in DISTS.items() if k != "exponential"}


def zscore(values, exact):
    """(mean - exact) / stderr per channel."""
    v = np.asarray(values, dtype=np.float64)
    se = v.std(axis=0, ddof=1) / np.sqrt(v.shape[0])
    return (v.mean(axis=0) - np.asarray(exact, dtype=np.float64)) / se


def assert_unbiased(values, exact, z=Z, what=""):
    zs = np.atleast_1d(zscore(values, exact))
    assert np.all(np.isfinite(zs)), f"{what}: non-finite z {zs}"
    assert np.all(np.abs(zs) <= z), f"{what}: mean is {zs} standard errors from the exact value"


def assert_detectably_biased(values, exact, z=Z, what=""):
    zs = np.atleast_1d(zscore(values, exact))
    assert np.all(np.abs(zs) > z), f"{what}: bias not detected (z = {zs})"


def variance_and_se(values):
    """Sample variance and its standard error sqrt((m4 - s^4) / R) (large-sample)."""
    v = np.asarray(values, dtype=np.float64)
    d = v - v.mean(axis=0)
    s2 = (d ** 2).mean(axis=0)
    m4 = (d ** 4).mean(axis=0)
    return s2 * len(v) / (len(v) - 1), np.sqrt(np.maximum(m4 - s2 ** 2, 0.0) / len(v))


BACKENDS = ("numpy", "drjit")


def drjit_backend():
    """The Dr.Jit array module in use (drjit.llvm / drjit.cuda, or .ad under a Mitsuba AD
    variant), after ``styletrace.jit.prepare_drjit()`` (a working libLLVM) when Dr.Jit is not
    loaded yet."""
    import sys
    if "drjit" not in sys.modules:
        from styletrace.jit import prepare_drjit
        prepare_drjit()
    from styletrace.estimators.arrays import backend_module
    return backend_module()


def run_estimates(estimator, dist, lanes, backend="numpy", seed=0, channels=None, dtype=np.float64):
    """One estimate per lane on the chosen backend (Dr.Jit: float32 kernel with a PCG32 carry)."""
    from styletrace.estimators import estimate_drjit, estimate_numpy
    if backend == "numpy":
        return estimate_numpy(
            estimator, dist, lanes, np.random.default_rng(seed), channels=channels, dtype=dtype
        )
    drjit_backend()  # Dr.Jit loaded with a working libLLVM
    return estimate_drjit(estimator, dist, lanes, seed=seed, channels=channels)
