"""The path kernel's MIS weight: finite for every pair of densities, with the power heuristic's
limits."""
import numpy as np

from styletrace.gate import mi
from styletrace.kernel.vertex import mis_power

BIG = [0.0, 1e-30, 1.0, 3.0, 1e19, 2.6e19, 1e30, 3.0e38, float("inf")]


def test_mis_power_is_finite_and_complementary():
    """Densities above ~1.8e19 overflow when squared in float32 (a grazing direction towards an
    area light reaches them): the weight must stay finite and the two strategies' weights sum to
    1."""
    a, b = np.meshgrid(np.array(BIG[1:], np.float32), np.array(BIG[1:], np.float32))
    a, b = a.ravel(), b.ravel()
    wa = np.asarray(mis_power(mi.Float(a), mi.Float(b)))
    wb = np.asarray(mis_power(mi.Float(b), mi.Float(a)))
    assert np.all(np.isfinite(wa)), list(zip(a[~np.isfinite(wa)], b[~np.isfinite(wa)]))
    np.testing.assert_allclose(wa + wb, 1.0, rtol=1e-6)


def test_mis_power_values_and_limits():
    a = np.array([1.0, 3.0, 2.6e19, 2.6e19, 1.0, float("inf"), 1.0, 0.0], np.float32)
    b = np.array([1.0, 1.0, 1.0, 2.6e19, 2.6e19, 1.0, float("inf"), 5.0], np.float32)
    want = np.where(a > 0, 1.0 / (1.0 + (b.astype(np.float64) / a) ** 2), 0.0)  # float64 reference
    want[np.isinf(a) & np.isfinite(b)] = 1.0
    got = np.asarray(mis_power(mi.Float(a), mi.Float(b)))
    np.testing.assert_allclose(got, want, rtol=1e-6, atol=1e-30)
