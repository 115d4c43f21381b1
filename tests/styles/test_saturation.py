import numpy as np
import pytest

from styletrace.styles import create

from .support import rejects, rejects_unknown, run


def paper_saturation(I, w):
    """S5.3 literally (float64), with I_max normalised to brightness u."""
    I = np.asarray(I, dtype=np.float64)
    u = I.mean(axis=1, keepdims=True)
    c_min = I.min(axis=1, keepdims=True)
    c_max = I.max(axis=1, keepdims=True)
    I_max = (I - c_min) / c_max
    u2 = I_max.mean(axis=1, keepdims=True)
    return w * np.repeat(u, 3, axis=1) + (1 - w) * I_max * u / u2


def test_hand_values():
    s = create("saturation")  # w = 0.5
    # (0.6,0.3,0): u=0.3, I_max=(1,.5,0), u'=.5 -> saturated (0.6,0.3,0); blend with (0.3,0.3,0.3)
    # (0.2,0.4,0.9): u=0.5, saturated = (0, 0.2, 0.7) * 0.5/(0.3) = (0, 1/3, 7/6)
    out = run(s, [(0.6, 0.3, 0.0), (0.2, 0.4, 0.9)])
    want = [(0.45, 0.3, 0.15), (0.25, 0.5 * 0.5 + 0.5 / 3, 0.25 + 7 / 12)]
    np.testing.assert_allclose(out, want, atol=1e-5)


@pytest.mark.parametrize("w", [0.0, 0.3, 0.5, 1.0])
def test_matches_supplement_formula(w):
    rng = np.random.default_rng(1)
    I = rng.uniform(0.0, 3.0, size=(64, 3)).astype(np.float32)
    np.testing.assert_allclose(
        run(create("saturation", w=w), I), paper_saturation(I, w), rtol=1e-5, atol=1e-5
    )


def test_w1_is_grey_and_w0_is_saturated_at_same_brightness():
    rng = np.random.default_rng(2)
    I = rng.uniform(0.0, 2.0, size=(32, 3)).astype(np.float32)
    u = I.astype(np.float64).mean(axis=1)
    grey = run(create("saturation", w=1.0), I)
    np.testing.assert_allclose(grey, np.repeat(u[:, None], 3, axis=1), atol=1e-6)
    sat = run(create("saturation", w=0), I)
    np.testing.assert_allclose(sat.min(axis=1), 0.0, atol=1e-6)          # one channel at zero
    np.testing.assert_allclose(sat.mean(axis=1), u, rtol=1e-5)           # same brightness
    d = I - I.min(axis=1, keepdims=True)  # same hue
    np.testing.assert_allclose(
        sat * d.sum(axis=1, keepdims=True), d * sat.sum(axis=1, keepdims=True), atol=1e-5
    )


def test_grey_and_black_inputs_are_returned_grey():
    # c_max = 0 (black) and u' = 0 (grey): no hue to saturate, result is I_min = (u,u,u)
    out = run(create("saturation", w=0.0), [(0, 0, 0), (0.5, 0.5, 0.5), (3.0, 3.0, 3.0)])
    np.testing.assert_allclose(out, [(0, 0, 0), (0.5, 0.5, 0.5), (3, 3, 3)], atol=1e-6)
    # almost grey: finite and bounded by 3u
    out = run(create("saturation", w=0.0), [(0.5, 0.5, 0.50000006)])
    assert np.all(np.isfinite(out)) and out.max() <= 1.5 + 1e-6


def test_parameters():
    assert "[0, 1]" in rejects("saturation", "w", 1.5)
    rejects("saturation", "w", -0.1)
    rejects("saturation", "w", "lots")
    rejects_unknown("saturation")
    assert create("saturation", w="0.25").w == 0.25
