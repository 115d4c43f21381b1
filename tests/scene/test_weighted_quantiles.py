"""`scene_defaults.weighted_quantiles`, spelled out for numpy 1.x (bpy pins numpy < 2), equals
numpy 2's weighted inverted-CDF quantiles, which the auto style defaults use."""
import numpy as np
import pytest

from styletrace.scene.defaults import weighted_quantiles


@pytest.mark.skipif(
    int(np.__version__.split(".")[0]) < 2,
    reason="the reference, np.quantile(weights=), needs numpy 2",
)
def test_equals_numpy2_with_real_weights():
    rng = np.random.default_rng(4)
    for _ in range(300):
        n = int(rng.integers(1, 60))
        values = np.round(rng.normal(size=n), 1)  # ties included
        weights = rng.integers(0, 4, size=n).astype(float) * rng.random(n)
        weights[rng.integers(n)] += 0.5  # at least one positive weight
        qs = [0.0, 0.1, 1 / 3, 0.5, 2 / 3, 0.9, 1.0]
        want = np.quantile(values, qs, weights=weights, method="inverted_cdf")
        assert weighted_quantiles(values, weights, qs) == [float(x) for x in want]
