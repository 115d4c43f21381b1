import numpy as np

from styletrace.styles import create

from .support import rejects, rejects_unknown, run


def hexc(h):
    return np.array([int(h[i:i + 2], 16) for i in (1, 3, 5)]) / 255.0


def test_hand_values_default_gradient():
    a = create("acp")
    assert a.per_sample is True
    # 'dusk': Y = 0.5 is a stop (#e07a5f); Y = 0 -> first stop scaled by 0.01; Y = 2 -> last stop
    # (clamped) * 2
    out = run(a, [(0.2, 0.5, 0.8), (0, 0, 0), (2, 2, 2), (-1, 0, 0)])
    np.testing.assert_allclose(out[0], 0.5 * hexc("#e07a5f"), atol=1e-6)
    np.testing.assert_allclose(out[1], 0.01 * hexc("#161a3a"), atol=1e-6)
    np.testing.assert_allclose(out[2], 2.0 * hexc("#fffbe6"), atol=1e-6)
    np.testing.assert_allclose(out[3], 0.01 * hexc("#161a3a"), atol=1e-6)


def test_custom_gradient_against_numpy():
    a = create("acp", gradient="0:0,0,0;1:1,0.5,0.25")
    I = np.random.default_rng(7).uniform(-0.2, 1.5, size=(50, 3))
    Y = I.mean(axis=1)
    t = np.clip(Y, 0, 1)[:, None]
    want = np.maximum(Y, 0.01)[:, None] * t * np.array([1, 0.5, 0.25])
    np.testing.assert_allclose(run(a, I), want, atol=1e-6)


def test_only_acp_is_per_sample():
    from styletrace.styles import style_class, style_names
    assert [n for n in style_names() if getattr(style_class(n), "per_sample", False)] == ["acp"]


def test_parameters():
    rejects("acp", "gradient", "0:#000000;0:#ffffff")
    rejects_unknown("acp")
