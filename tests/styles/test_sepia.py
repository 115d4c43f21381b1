import numpy as np

from styletrace.styles import create

from .support import rejects, rejects_unknown, run

C1 = np.array([0xc4, 0xa2, 0x7a]) / 255.0


def test_default_is_linear_ramp_to_sepia_and_extrapolates():
    s = create("sepia")
    I = [(0.3, 0.6, 0.9), (0, 0, 0), (3, 3, 3), (10, 0, 2)]
    u = np.array([0.6, 0.0, 3.0, 4.0])
    np.testing.assert_allclose(run(s, I), u[:, None] * C1[None, :], rtol=1e-5, atol=1e-6)


def test_custom_two_stop_gradient():
    s = create("sepia", gradient="0.2:0.1,0.1,0.1;0.7:0.9,0.5,0.3")
    c0, c1 = np.array([0.1, 0.1, 0.1]), np.array([0.9, 0.5, 0.3])
    I = np.array(
        [(0.0, 0.0, 0.0), (0.2, 0.2, 0.2), (0.7, 0.7, 0.7), (1.5, 0.3, 0.6), (-0.3, 0.0, 0.0)]
    )
    u = I.mean(axis=1)
    want = c0 + (c1 - c0) * ((u - 0.2) / 0.5)[:, None]
    np.testing.assert_allclose(run(s, I), want, atol=1e-5)


def test_affine_form_matches_apply():
    s = create("sepia", gradient="0.1:#102030;0.9:#f0e0d0")
    A, b = s.affine()
    A, b = np.array(A), np.array(b)
    assert A.shape == (3, 3) and b.shape == (3,)
    assert np.linalg.matrix_rank(A) == 1
    I = np.random.default_rng(3).uniform(-0.5, 5.0, size=(40, 3))
    np.testing.assert_allclose(run(s, I), I @ A.T + b, rtol=1e-5, atol=1e-5)


def test_more_than_two_stops_refused():
    msg = rejects("sepia", "gradient", "0:#000000;0.5:#808080;1:#ffffff")
    assert "2 stops" in msg and "affine" in msg
    rejects("sepia", "gradient", "dusk")
    rejects("sepia", "gradient", "0:#000000")          # one stop: not a gradient at all
    rejects_unknown("sepia")
    assert create("sepia", gradient="sepia").gradient.stops == create("sepia").gradient.stops
