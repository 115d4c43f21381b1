import numpy as np

from styletrace.styles import create

from .support import rejects, rejects_unknown, run


def test_hand_values():
    # 1.5 * (x - 0.5) + 0.5
    out = run(create("contrast"), [(0.5, 0.0, 1.0), (0.2, 0.7, 2.0)])
    np.testing.assert_allclose(out, [(0.5, -0.25, 1.25), (0.05, 0.8, 2.75)], atol=1e-6)


def test_custom_factor_and_pivot():
    I = np.random.default_rng(8).uniform(-1, 3, size=(30, 3))
    out = run(create("contrast", c=0.3, pivot=0.1), I)
    np.testing.assert_allclose(out, 0.3 * (I - 0.1) + 0.1, atol=1e-6)
    np.testing.assert_allclose(run(create("contrast", c=0), I), np.full_like(I, 0.5), atol=1e-7)


def test_parameters():
    rejects("contrast", "c", -1.0)
    rejects("contrast", "pivot", "high")
    rejects("contrast", "c", float("nan"))
    rejects_unknown("contrast")
