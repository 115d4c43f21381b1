import numpy as np

from styletrace.styles import create

from .support import rejects, rejects_unknown, run

SPEC = "0.2:0,0,0;0.6:1,0.5,0.25;1:0.5,1,0"


def numpy_map(u):
    xs = [0.2, 0.6, 1.0]
    cols = np.array([(0, 0, 0), (1, 0.5, 0.25), (0.5, 1, 0)])
    return np.stack([np.interp(u, xs, cols[:, k]) for k in range(3)], axis=1)


def test_interpolation_and_clamping_at_both_ends():
    m = create("color_map", gradient=SPEC)
    u = np.array([-5.0, 0.0, 0.2, 0.4, 0.6, 0.8, 1.0, 1.3, 100.0])
    I = np.stack([u, u, u], axis=1)
    out = run(m, I)
    np.testing.assert_allclose(out, numpy_map(u), atol=1e-6)
    np.testing.assert_allclose(out[0], (0, 0, 0), atol=1e-7)        # below the first stop
    np.testing.assert_allclose(out[-1], (0.5, 1, 0), atol=1e-7)     # above the last stop


def test_brightness_is_channel_mean():
    m = create("color_map", gradient=SPEC)
    np.testing.assert_allclose(run(m, [(1.2, 0.0, 0.0)]), numpy_map(np.array([0.4])), atol=1e-6)


def test_default_preset_hits_its_stops():
    m = create("color_map")
    out = run(m, [(0.5,) * 3, (5.0,) * 3])
    np.testing.assert_allclose(out[0], np.array([0xe0, 0x7a, 0x5f]) / 255, atol=1e-6)
    np.testing.assert_allclose(out[1], np.array([0xff, 0xfb, 0xe6]) / 255, atol=1e-6)


def test_parameters():
    rejects("color_map", "gradient", "0:#zzzzzz;1:#ffffff")
    rejects("color_map", "gradient", "1:#000000;0:#ffffff")
    rejects("color_map", "gradient", "0:#000000")
    rejects("color_map", "gradient", "nopreset")
    rejects_unknown("color_map")
    assert (
        create("color_map", gradient=[(0, (0, 0, 0)), (2, (1, 1, 1))]).gradient.stops[1][0] == 2.0
    )
