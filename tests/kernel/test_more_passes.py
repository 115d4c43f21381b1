"""Position, UV, Mist, the pass indices and Emission against analytic answers: a pinhole camera
10 above planes whose points, texture coordinates and distances the tests write themselves."""
import math

import numpy as np
import pytest

from styletrace.errors import UsageError
from styletrace.gate import mi
from styletrace.kernel.data_passes import render_data_passes
from styletrace.kernel.mist import Mist, parse_mist
from styletrace.kernel.pass_indices import indices_of, shape_id

T = mi.ScalarTransform4f
W, H, FOV, D = 32, 24, 40.0, 10.0
F = (W / 2) / math.tan(math.radians(FOV / 2))


def scene(**shapes):
    cam = T().look_at(origin=[0, 0, D], target=[0, 0, 0], up=[0, 1, 0])
    return mi.load_dict({"type": "scene", **shapes,
                         "sensor": {"type": "perspective", "fov": FOV, "to_world": cam,
                                    "film": {"type": "hdrfilm", "width": W, "height": H}}})


def wall(**extra):
    return {"type": "rectangle", "to_world": T().scale(50.0), **extra}


def test_ids_carry_the_indices():
    assert shape_id("shape_3", 7, 5) == "shape_3__ob7__ma5"
    assert shape_id("shape_3", 0, 0) == "shape_3" and shape_id("s", 0, 4) == "s__ma4"
    for ident, want in (("shape_3__ob7__ma5", (7, 5)), ("s__ma4", (0, 4)), ("x__ob2", (2, 0)),
                        ("plain", (0, 0)), ("", (0, 0)), ("a__ob7__ma5_b", (0, 0))):
        assert indices_of(ident) == want, ident


def test_position_and_uv_of_a_wall():
    """The wall z = 0 fills the view: the first sample's point lies inside its pixel's square on
    the wall (footprint D / F), its z 0; the rectangle's uv maps x, y in [-50, 50] to u and
    Blender's v; every sample hits (A = 1)."""
    out = render_data_passes(scene(w=wall()), ["position", "uv"], spp=8, seed=2)
    p, uv = out["position"], out["uv"]
    x = (np.arange(W) + 0.5 - W / 2) * D / F
    y = (H / 2 - np.arange(H) - 0.5) * D / F
    gx, gy = np.meshgrid(x, y)
    half = 0.5 * D / F + 1e-5
    assert (np.abs(p[..., 0] - gx) <= half).all() and (np.abs(p[..., 1] - gy) <= half).all()
    assert np.abs(p[..., 2]).max() < 1e-5
    # Mitsuba's rectangle: (u, v) = ((x + 1) / 2, (y + 1) / 2), its v = 0 an image's top row;
    # Blender's v = 0 is the bottom row: 1 - v
    np.testing.assert_allclose(uv[..., 0], (gx / 50 + 1) / 2, atol=half / 100)
    np.testing.assert_allclose(uv[..., 1], (1 - gy / 50) / 2, atol=half / 100)
    assert (uv[..., 2] == 1).all()


@pytest.mark.parametrize("falloff", ["linear", "quadratic", "inverse_quadratic"])
def test_mist_at_known_distances(falloff):
    """Each pixel's mist is its samples' mean of t^k, t = (distance - start) / depth clamped,
    bounded by its value at the pixel's nearest and farthest points of the wall; the empty world
    beside a small square is 1."""
    mist = Mist(9.0, 2.0, falloff)
    out = render_data_passes(scene(w=wall()), ["mist"], spp=16, seed=1, mist=mist)["mist"]
    xs = (np.arange(W + 1) - W / 2) * D / F
    ys = (H / 2 - np.arange(H + 1)) * D / F
    gx, gy = np.meshgrid(xs, ys)
    power = {"linear": 1.0, "quadratic": 2.0, "inverse_quadratic": 0.5}[falloff]
    m = np.clip((np.sqrt(gx ** 2 + gy ** 2 + D ** 2) - 9.0) / 2.0, 0, 1) ** power
    corners = np.stack([m[:-1, :-1], m[1:, :-1], m[:-1, 1:], m[1:, 1:]])
    assert (out >= corners.min(0) - 1e-5).all() and (out <= corners.max(0) + 1e-5).all()
    assert out.max() - out.min() > 0.2
    small = render_data_passes(scene(s={"type": "rectangle"}), ["mist"], 4, mist=mist)["mist"]
    assert (small[:2, :2] == 1).all() and small.min() == pytest.approx(0.5 ** power, abs=0.01)


def test_two_objects_with_pass_indices():
    """A square with object index 3 and material index 5 in front of a wall with object index 7;
    the world beside is 0; the indices are a first sample's, never blends."""
    near = {"type": "rectangle", "to_world": T().translate([0, 0, 2.0]).scale(1.5)}
    sc = scene(**{"wall__ob7": wall(), "square__ob3__ma5": near})
    out = render_data_passes(sc, ["object_index", "material_index"], spp=4, seed=0)
    ob, ma = out["object_index"], out["material_index"]
    assert set(np.unique(ob)) == {3.0, 7.0} and set(np.unique(ma)) == {0.0, 5.0}
    assert ob[H // 2, W // 2] == 3 and ob[0, 0] == 7 and ma[H // 2, W // 2] == 5
    np.testing.assert_array_equal(ma == 5, ob == 3)
    plain = render_data_passes(scene(s={"type": "rectangle"}), ["object_index"], 2)
    assert (plain["object_index"] == 0).all()


def test_an_emitter_seen_directly():
    """An area emitter of radiance (1, 2, 3) facing the camera: its pixels hold it, a diffuse
    wall behind and the world (a constant environment) 0; edge pixels a share of it."""
    light = {"type": "rectangle", "to_world": T().translate([0, 0, 1.0]),
             "emitter": {"type": "area", "radiance": {"type": "rgb", "value": [1.0, 2.0, 3.0]}}}
    sky = {"type": "constant", "radiance": {"type": "rgb", "value": [5.0, 5.0, 5.0]}}
    e = render_data_passes(scene(l=light, sky=sky), ["emission"], spp=16, seed=3)["emission"]
    side = (1.0 * F / (D - 1.0))  # the light's half width in pixels
    centre = e[H // 2 - 2:H // 2 + 2, W // 2 - 2:W // 2 + 2].reshape(-1, 3)
    np.testing.assert_allclose(centre, np.tile([1.0, 2.0, 3.0], (16, 1)), atol=1e-6)
    assert (e[:2, :2] == 0).all() and side > 2
    edge = (e[..., 0] > 0) & (e[..., 0] < 1)
    np.testing.assert_allclose(e[edge] / e[edge][:, :1], np.tile([1, 2, 3], (edge.sum(), 1)),
                               rtol=1e-5)


def test_bad_mist_settings_are_refused_in_one_line():
    assert parse_mist("5,25,QUADRATIC") == Mist() and parse_mist(None) == Mist()
    assert parse_mist((1, 2, "linear")) == Mist(1.0, 2.0, "linear")
    for bad in ("5,25,cubic", "5,0,linear", "-1,2,linear", "5,25", "a,2,linear"):
        with pytest.raises(UsageError) as info:
            parse_mist(bad, "--mist")
        assert str(info.value).startswith(f"bad value {bad!r} for --mist: expected")
        assert "quadratic, linear, inverse_quadratic" in str(info.value)
        assert "\n" not in str(info.value)
