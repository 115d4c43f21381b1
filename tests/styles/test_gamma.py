import numpy as np

from styletrace.styles import create

from .support import rejects, rejects_unknown, run


def test_hand_values():
    out = run(create("gamma", gamma=2), [(0.25, 1.0, 4.0), (0.0, -1.0, 0.09)])
    np.testing.assert_allclose(out, [(0.5, 1.0, 2.0), (0.0, 0.0, 0.3)], atol=1e-6)


def test_default_against_numpy():
    I = np.random.default_rng(9).uniform(0, 3, size=(30, 3))
    np.testing.assert_allclose(run(create("gamma"), I), I ** (1 / 2.2), rtol=1e-5)


def test_parameters():
    msg = rejects("gamma", "gamma", 0.0)
    assert "[0.1, 1e+06]" in msg
    rejects("gamma", "gamma", 0.09)  # 1/gamma > 10 overflows float32 on bright radiance
    rejects("gamma", "gamma", float("inf"))
    rejects("gamma", "gamma", -2.2)
    rejects_unknown("gamma")
