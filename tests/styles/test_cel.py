import numpy as np
import pytest

from styletrace.styles import create

from .support import rejects, rejects_unknown, run


def test_bands_keep_colour():
    c = create("cel", thresholds=0.75, levels="0.4,0.95")  # u < 0.75 -> 0.4, u >= 0.75 -> 0.95
    I = np.array([(0.3, 0.6, 0.9), (0.1, 0.2, 0.3), (1.5, 1.5, 3.0)], dtype=np.float32)
    u = I.astype(np.float64).mean(axis=1)
    target = np.array([0.4, 0.4, 0.95])
    np.testing.assert_allclose(run(c, I), I * (target / u)[:, None], rtol=1e-6)


def test_band_edge_exactly_at_threshold():
    c = create("cel", thresholds=0.75, levels="0.4,0.95")
    I = np.array([(0.75, 0.75, 0.75), (0.75, 0.5, 1.0), (0.7499, 0.7499, 0.7499)], dtype=np.float32)
    # u is exactly the threshold
    assert np.float32(I[0].sum()) * np.float32(1 / 3) == np.float32(0.75)
    out = run(c, I)
    np.testing.assert_allclose(out[0], [0.95] * 3, rtol=1e-6)                 # u >= t: upper band
    np.testing.assert_allclose(out[1], I[1] * (0.95 / 0.75), rtol=1e-6)
    # just below: lower band
    np.testing.assert_allclose(out[2], [0.4] * 3, rtol=1e-6)


def test_zero_brightness_is_grey_at_first_level():
    out = run(create("cel", levels="0.4,0.95"), [(0, 0, 0), (-0.3, 0.1, 0.2)])
    np.testing.assert_allclose(out, [(0.4,) * 3] * 2, atol=1e-7)
    assert np.all(np.isfinite(out))


def test_unresolved_auto_thresholds_are_evenly_spaced():
    # thresholds default to auto (scene quantiles, tests/scene/test_defaults.py); a style never
    # resolved on a scene splits [0, 1] evenly: 0.5 for two levels, 1/3 and 2/3 for three
    assert create("cel").thresholds is None
    out = run(create("cel", levels="0.4,0.95"), [(0.49,) * 3, (0.5,) * 3])
    np.testing.assert_allclose(out, [(0.4,) * 3, (0.95,) * 3], rtol=1e-6)
    c = create("cel", levels="0.1,0.5,0.9")
    np.testing.assert_allclose(
        run(c, [(0.3,) * 3, (0.34,) * 3, (0.67,) * 3])[:, 0], [0.1, 0.5, 0.9], rtol=1e-6
    )


def test_unresolved_auto_levels_are_evenly_spaced_in_lightness():
    # three bands by default; never resolved on a scene, the levels are L* 30, 57.5 and 85
    from styletrace.styles.tone import lightness
    c = create("cel")
    assert c.levels is None and c.band_count == 3
    out = run(c, [(0.2,) * 3, (0.5,) * 3, (0.8,) * 3])[:, 0]
    np.testing.assert_allclose(lightness(out), [30.0, 57.5, 85.0], atol=0.02)


def test_several_thresholds():
    c = create("cel", thresholds="0.2,0.5", levels="0.1,0.4,0.9")
    u = np.array([0.1, 0.2, 0.35, 0.5, 2.0])
    I = np.stack([u, u, u], axis=1)
    np.testing.assert_allclose(
        run(c, I), np.repeat(np.array([0.1, 0.4, 0.4, 0.9, 0.9])[:, None], 3, 1), rtol=1e-6
    )


def test_parameters():
    msg = rejects("cel", "thresholds", "0.5,0.2", levels="0.1,0.2,0.3")
    assert "increase" in msg
    # 1 threshold needs 2 levels
    msg = rejects("cel", "levels", "0.1,0.2,0.3", thresholds="0.5")
    assert "expected 2 levels" in msg
    rejects("cel", "levels", "-0.1,0.5")
    rejects("cel", "thresholds", "")
    rejects_unknown("cel")


@pytest.mark.parametrize("value", ["0.5", [0.5], (0.5,), 0.5])
def test_threshold_spellings(value):
    assert create("cel", thresholds=value).thresholds == (0.5,)
