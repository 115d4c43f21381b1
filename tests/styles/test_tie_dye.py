import numpy as np

from styletrace.styles import create

from .support import rejects, rejects_unknown, run


def printed(I):
    """The supplement's three waves (S5.5), samples clamped to [-1, 4]."""
    x = np.clip(np.asarray(I, dtype=np.float64), -1.0, 4.0)
    r, g, b = x[:, 0], x[:, 1], x[:, 2]
    return np.stack([(1 - np.cos(2 * np.pi * (r + 1))) / 2,
                     (1 - np.cos(2.15 * np.pi * (g + 1.13))) / 2,
                     (1 - np.cos(2.3 * np.pi * (b + 1.29))) / 2], axis=1)


def test_hand_values():
    # r = 0: (1 - cos(2 pi))/2 = 0; r = 0.5: (1 - cos(3 pi))/2 = 1; r = 0.25: (1 - cos(2.5 pi))/2 =
    # 0.5 g = 2/2.15 - 1.13: 2.15 pi (g + 1.13) = 2 pi -> 0; b = -1.29 is below -1, clamps to -1:
    # (1 - cos(2.3 pi * 0.29))/2
    out = run(create("tie_dye"), [(0.0, 2 / 2.15 - 1.13, -1.29), (0.5, 0.0, 0.0), (0.25, 0.0, 0.0)])
    np.testing.assert_allclose(out[:, 0], [0.0, 1.0, 0.5], atol=1e-6)
    assert abs(out[0, 1]) < 1e-5
    assert abs(out[0, 2] - (1 - np.cos(2.3 * np.pi * 0.29)) / 2) < 1e-6


def test_matches_printed_formulas_with_clamp():
    I = np.random.default_rng(4).uniform(-2.0, 6.0, size=(200, 3)).astype(np.float32)
    np.testing.assert_allclose(run(create("tie_dye"), I), printed(I), atol=1e-5)
    # above 4 behaves as 4, below -1 as -1
    np.testing.assert_allclose(run(create("tie_dye"), [(7, 9, 100), (-5, -2, -1.5)]),
                               printed([(4, 4, 4), (-1, -1, -1)]), atol=1e-5)


def test_channel_functions_for_the_fit():
    s = create("tie_dye")
    assert s.domain() == (-1.0, 4.0)
    x = np.linspace(-1.5, 4.5, 301)
    want = printed(np.stack([x, x, x], axis=1))
    for c, f in enumerate(s.channel_functions()):
        np.testing.assert_allclose(f(x), want[:, c], atol=1e-12)


def test_custom_parameters():
    s = create("tie_dye", frequencies="1", phases="0,0.5,0.25")
    assert s.frequencies == (1.0, 1.0, 1.0)
    x = np.array([[0.3, 0.3, 0.3]])
    want = (1 - np.cos(np.pi * (0.3 + np.array([0.0, 0.5, 0.25])))) / 2
    np.testing.assert_allclose(run(s, x)[0], want, atol=1e-6)


def test_parameters():
    rejects("tie_dye", "frequencies", "0,1,2")
    rejects("tie_dye", "frequencies", "-1")
    msg = rejects("tie_dye", "phases", "1,2")
    assert "1 or 3" in msg
    msg = rejects("tie_dye", "domain_max", -2.0)
    assert "domain_min" in msg
    rejects_unknown("tie_dye")
