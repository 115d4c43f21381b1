"""What each style tells the adaptive controller: its jumps (`step_thresholds`) and its
curvature."""
import numpy as np
import pytest

from styletrace.styles import create, style_names

from .support import color, tonp, vertex

#: brightness grid along the grey axis: fine enough that a continuous style moves little between
#: neighbours
U = np.arange(0.01, 1.6, 1e-3, dtype=np.float32)
LANES = 64


P = np.random.default_rng(0).uniform(-1, 1, (LANES, 3))


def vertices(repeat=1):
    """LANES random vertices facing the camera; `repeat` copies of each, consecutively."""
    p = np.repeat(P, repeat, axis=0)
    return vertex(p=p, n=np.tile([0, 0, 1], (len(p), 1)), wo=np.tile([0, 0, 1], (len(p), 1)))


def along_grey(style, v=None):
    """g(u (1, 1, 1)) at every lane for every u of the grid, in one kernel: (len(U), LANES, 3)."""
    v = vertices(len(U))
    I = np.tile(U, LANES)[:, None].repeat(3, axis=1)
    return tonp(style.apply(color(I), v)).reshape(LANES, len(U), 3).transpose(1, 0, 2)


def thresholds_of(style, v) -> np.ndarray:
    """(k, LANES) the style's thresholds per lane (+inf: none)."""
    ts = style.step_thresholds(v)
    return np.array([np.broadcast_to(np.array(t, dtype=np.float64), (LANES,)) for t in ts]).reshape(
        -1, LANES
    )


@pytest.mark.parametrize("name", [n for n in style_names()] + ["contrast+sepia"])
def test_every_jump_is_a_declared_threshold(name):
    # brute force along the grey axis: between two neighbouring brightnesses where g jumps (moves
    # more than a continuous style can over 1e-3), one of the lane's declared thresholds must lie
    style = create(name)
    v = vertices()
    g = along_grey(style)
    jumps = np.abs(np.diff(g, axis=0)).max(axis=-1) > 0.05      # (len(U) - 1, LANES)
    ts = thresholds_of(style, v)
    for i, lane in zip(*np.nonzero(jumps)):
        assert np.any((ts[:, lane] >= U[i] - 1e-6) & (ts[:, lane] <= U[i + 1] + 1e-6)), \
            (name, U[i], ts[:, lane])
    # and every finite threshold in range is a real jump
    for k, lane in zip(*np.nonzero(np.isfinite(ts) & (ts > U[1]) & (ts < U[-2]))):
        i = np.searchsorted(U, ts[k, lane])
        assert np.abs(g[i + 1, lane] - g[i - 2, lane]).max() > 0.05, (name, ts[k, lane])


def test_the_step_styles_declare_thresholds():
    v = vertices()
    for name in ("cel", "hatching", "halftone"):
        assert np.isfinite(thresholds_of(create(name), v)).any(), name
    assert thresholds_of(create("cel", thresholds=(0.3, 0.8), levels=(0.1, 0.5, 0.9)), v)[
        :, 0
    ].tolist() == pytest.approx([0.3, 0.8])


@pytest.mark.parametrize(
    "name", ["identity", "contrast", "sepia", "contrast+sepia", "cel", "hatching", "halftone"]
)
def test_affine_and_step_styles_have_no_curvature(name):
    import mitsuba as mi
    c = tonp(create(name).curvature(color(np.full((LANES, 3), 0.4)), vertices(), mi.Float(0.05)))
    assert np.all(c == 0.0)


def test_gamma_curvature_is_g_second_derivative():
    import mitsuba as mi
    gamma = 2.2
    I = np.array([[0.2, 0.5, 0.9]] * LANES, dtype=np.float32)
    c = tonp(create("gamma", gamma=gamma).curvature(color(I), vertices(), mi.Float(0.01)))
    p = 1.0 / gamma
    exact = p * (p - 1.0) * I.astype(np.float64) ** (p - 2.0)
    # central second difference: error h^2 g''''/12, below 1e-3 relative here; float32 cancellation
    # (eps |g| / h^2 ~ 1e-7 / 1e-4) another 1e-3
    np.testing.assert_allclose(c, exact, rtol=5e-3)


def test_color_map_curvature_sees_its_kinks_only():
    import mitsuba as mi
    style = create("color_map", range=(0.0, 1.0))
    stops = [s for s, _ in style.gradient.stops]
    v = vertices()
    h = mi.Float(0.01)
    # halfway between two stops the map is linear: nothing but float32 rounding
    mid = 0.5 * (stops[0] + stops[1])
    flat = tonp(style.curvature(mi.Color3f(mid), v, h))
    assert np.abs(flat).max() < 1e-2
    # at the clamp of the range's upper end the slope jumps: |jump of g'| / h
    kink = tonp(style.curvature(mi.Color3f(1.0), v, h))
    assert np.abs(kink).max() > 1.0
