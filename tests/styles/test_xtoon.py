import math

import numpy as np

from styletrace.gate import mi
from styletrace.styles import create

from .support import rejects, rejects_unknown, run, vertex

# three flat bands, written independently of the gradient parser
STOPS = [(0.0, (0.1, 0.0, 0.0)), (0.5, (0.5, 0.2, 0.0)), (1.0, (1.0, 0.8, 0.4))]
SPEC = ";".join(f"{p}:{c[0]},{c[1]},{c[2]}" for p, c in STOPS)


def ramp(t):
    xs = [p for p, _ in STOPS]
    return np.stack([np.interp(t, xs, [c[k] for _, c in STOPS]) for k in range(3)], axis=1)


def xtoon_np(p, n, wo, view, light, mode, r, z_min, z_max, detail_color, cam=(0, 0, 0)):
    n = n / np.linalg.norm(n, axis=1, keepdims=True)
    n = np.where((n * wo).sum(axis=1, keepdims=True) < 0, -n, n)
    l = np.asarray(light, dtype=np.float64) / np.linalg.norm(light)
    tone = n @ l
    if mode == "orientation":
        D = np.abs((n * wo).sum(axis=1)) ** r
    else:
        z = np.clip((p - np.asarray(cam)) @ np.asarray(view), z_min, z_max)
        D = 1 - np.log(z / z_min) / np.log(z_max / z_min)
    return D[:, None] * ramp(tone) + (1 - D[:, None]) * np.asarray(detail_color)


def test_hand_values_orientation():
    x = create("xtoon", light_dir="0,0,1", gradient=SPEC, detail_color="0,0,1", r=2)
    assert x.closed_form
    # n = z, wo at n.wo = 0.8: D = 0.64, tone = 1 -> (1, .8, .4); grazing wo: D = 0 -> detail colour
    out = run(x, np.zeros((2, 3)), vertex(n=[(0, 0, 1), (0, 0, 1)], wo=[(0, 0.6, 0.8), (1, 0, 0)]))
    np.testing.assert_allclose(
        out[0], 0.64 * np.array([1.0, 0.8, 0.4]) + 0.36 * np.array([0, 0, 1]), atol=1e-6
    )
    np.testing.assert_allclose(out[1], [0, 0, 1], atol=1e-6)


def test_hand_values_depth():
    x = create(
        "xtoon",
        mode="depth",
        light_dir="0,0,-1",
        z_min=1,
        z_max=100,
        gradient=SPEC,
        detail_color="1,1,1",
    )
    # camera at origin looking along +z; z = 10 -> D = 1 - log 10 / log 100 = 0.5; tone = n.l = 1 (n
    # faces -z)
    p = [(0, 0, 10), (3, 0, 0.5), (0, 1, 1000)]
    out = run(
        x, np.zeros((3, 3)), vertex(p=p, n=[(0, 0, -1)] * 3, wo=[(0, 0, -1)] * 3, view=(0, 0, 1))
    )
    np.testing.assert_allclose(out[0], 0.5 * np.array([1.0, 0.8, 0.4]) + 0.5, atol=1e-6)
    # nearer than z_min: full detail
    np.testing.assert_allclose(out[1], [1.0, 0.8, 0.4], atol=1e-6)
    np.testing.assert_allclose(out[2], [1, 1, 1], atol=1e-6)         # beyond z_max: detail colour


def test_matches_closed_form_on_random_vertices():
    rng = np.random.default_rng(6)
    N = 100
    p = rng.uniform(-5, 5, size=(N, 3)) + np.array([0, 0, 8])
    n = rng.normal(size=(N, 3))
    wo = rng.normal(size=(N, 3))
    wo /= np.linalg.norm(wo, axis=1, keepdims=True)
    view = np.array([0.0, 0.6, 0.8])
    for mode in ("orientation", "depth"):
        kw = dict(
            light_dir=(1.0, 1.0, 0.2),
            mode=mode,
            r=1.5,
            z_min=2.0,
            z_max=12.0,
            detail_color=(0.9, 0.8, 0.7),
        )
        x = create("xtoon", gradient=SPEC, **kw)
        x.camera = (0.5, -1.0, 0.0)
        want = xtoon_np(p, n, wo, view, kw["light_dir"], mode, kw["r"], kw["z_min"], kw["z_max"],
                        kw["detail_color"], cam=x.camera)
        got = run(x, np.zeros((N, 3)), vertex(p=p, n=n, wo=wo, view=view))
        np.testing.assert_allclose(got, want, atol=1e-5, err_msg=mode)


def test_prepare_reads_camera_position():
    scene = mi.load_dict(
        {
            "type": "scene",
            "sensor": {
                "type": "perspective",
                "to_world": mi.ScalarTransform4f().look_at(
                    origin=[1, 2, 5], target=[0, 0, 0], up=[0, 1, 0]
                ),
            },
        }
    )
    x = create("xtoon", mode="depth")
    x.prepare(scene)
    np.testing.assert_allclose(x.camera, (1, 2, 5), atol=1e-6)


def test_default_gradient_has_three_bands():
    x = create("xtoon")
    cols = {tuple(c) for _, c in x.gradient.stops}
    assert len(cols) == 3 and math.isclose(x.r, 2.0)


def test_parameters():
    rejects("xtoon", "mode", "fancy")
    rejects("xtoon", "r", -1.0)
    rejects("xtoon", "z_min", 0.0)
    msg = rejects("xtoon", "z_max", 0.5, z_min=1.0)   # below z_min
    assert "z_min" in msg
    # unresolved auto ends (mi.render called directly): 1 and 10, a decade from the end that is
    # given
    assert create("xtoon").depth_range() == (1.0, 10.0)
    assert create("xtoon", z_max=0.5).depth_range() == (0.05, 0.5)
    assert create("xtoon", z_min=20).depth_range() == (20.0, 200.0)
    rejects("xtoon", "light_dir", "0,0,0")
    rejects("xtoon", "gradient", "not a gradient")
    rejects_unknown("xtoon")
