import numpy as np
import pytest

from styletrace.gate import mi
from styletrace.styles import create

from .support import rejects, rejects_unknown, run, vertex


def gooch_np(n, wo, l, kd, blue, yellow, alpha, beta):
    """Gooch et al. 1998 tone, warm towards the light, normals flipped to the viewer (float64)."""
    n = n / np.linalg.norm(n, axis=1, keepdims=True)
    n = np.where((n * wo).sum(axis=1, keepdims=True) < 0, -n, n)
    l = np.asarray(l, dtype=np.float64) / np.linalg.norm(l)
    t = ((1 + n @ l) / 2)[:, None]
    cool = np.asarray(blue) + alpha * np.asarray(kd)
    warm = np.asarray(yellow) + beta * np.asarray(kd)
    return t * warm + (1 - t) * cool


def test_hand_values():
    g = create("gooch", light_dir="0,1,0")
    assert g.closed_form
    n = [(0, 1, 0), (0, -1, 0), (0, -1, 0), (1, 0, 0), (0, 5, 0)]
    wo = [(0, 1, 0), (0, -1, 0), (0, 1, 0), (1, 0, 0), (0, 1, 0)]
    warm = (0.3 + 0.4, 0.3 + 0.4, 0.0 + 0.4)      # yellow + 0.5 k_d
    cool = (0.0 + 0.2, 0.0 + 0.2, 0.55 + 0.2)     # blue + 0.25 k_d
    mid = tuple((a + b) / 2 for a, b in zip(warm, cool))
    # lit side; unlit side seen from below; back face seen from above (flipped); grazing;
    # unnormalised n
    want = [warm, cool, warm, mid, warm]
    out = run(g, np.ones((5, 3)) * 123.0, vertex(n=n, wo=wo))   # the radiance estimate is ignored
    np.testing.assert_allclose(out, want, atol=1e-6)


def test_matches_closed_form_on_random_vertices():
    rng = np.random.default_rng(5)
    n = rng.normal(size=(100, 3))
    wo = rng.normal(size=(100, 3))
    wo /= np.linalg.norm(wo, axis=1, keepdims=True)
    kw = dict(
        light_dir=(0.3, 2.0, -0.5),
        k_d=(0.2, 0.6, 0.4),
        blue=(0, 0.1, 0.7),
        yellow=(0.5, 0.4, 0),
        alpha=0.4,
        beta=0.3,
    )
    g = create("gooch", **kw)
    want = gooch_np(
        n, wo, kw["light_dir"], kw["k_d"], kw["blue"], kw["yellow"], kw["alpha"], kw["beta"]
    )
    np.testing.assert_allclose(run(g, np.zeros((100, 3)), vertex(n=n, wo=wo)), want, atol=1e-5)


def test_defaults_match_the_brief():
    g = create("gooch")
    # light_dir is auto: from the camera (test_auto_light_follows_the_camera); unprepared: the
    # brief's 0,1,0.3
    assert g.light_dir is None and np.allclose(g.light(), np.array([0, 1, 0.3]) / np.hypot(1, 0.3))
    assert g.k_d == (0.8, 0.8, 0.8)
    assert (
        g.blue == (0.0, 0.0, 0.55)
        and g.yellow == (0.3, 0.3, 0.0)
        and g.alpha == 0.25
        and g.beta == 0.5
    )
    assert g.default_inner == 0


@pytest.mark.parametrize("style", ["gooch", "xtoon"])
@pytest.mark.parametrize("origin, up", [((0, 1, 5), (0, 1, 0)), ((4, -3, 1.5), (0, 0, 1))])
def test_auto_light_follows_the_camera(style, origin, up):
    # light_dir auto = normalize(up - 0.3 forward): above the picture for y-up and z-up scenes alike
    scene = mi.load_dict(
        {
            "type": "scene",
            "sensor": {
                "type": "perspective",
                "to_world": mi.ScalarTransform4f().look_at(origin=origin, target=[0, 0, 0], up=up),
            },
        }
    )
    g = create(style)
    g.prepare(scene)
    f = -np.array(origin, dtype=float) / np.linalg.norm(origin)
    cam_up = np.array(up, dtype=float) - (np.array(up) @ f) * f
    want = cam_up / np.linalg.norm(cam_up) - 0.3 * f
    np.testing.assert_allclose(g.light(), want / np.linalg.norm(want), atol=1e-3)
    # the light is above, not beside the scene
    assert np.dot(g.light(), up) > 0.9
    assert create(style, light_dir="1,0,0").light() == (1.0, 0.0, 0.0)   # an explicit value wins


def test_parameters():
    rejects("gooch", "light_dir", "0,0,0")
    rejects("gooch", "light_dir", "1,2")
    rejects("gooch", "k_d", "-0.1,0.5,0.5")
    rejects("gooch", "alpha", -1.0)
    rejects("gooch", "beta", "warm")
    rejects_unknown("gooch")
