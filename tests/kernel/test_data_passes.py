"""The data passes (Depth, Normal, Vector) against analytic answers: pinhole cameras looking at
planes, whose pixels the tests place with their own formulas (not the module's `View`)."""
import math

import numpy as np
import pytest

from styletrace.errors import SceneError, UsageError
from styletrace.gate import mi
from styletrace.kernel.data_passes import (
    BACKGROUND_DEPTH,
    Motion,
    View,
    parse_passes,
    render_data_passes,
)

T = mi.ScalarTransform4f
W, H, FOV = 32, 24, 40.0
#: focal length in pixels of the pinhole below (Mitsuba's fov spans the width)
F = (W / 2) / math.tan(math.radians(FOV / 2))
ALL = ("depth", "normal", "vector")


def matrix(t) -> np.ndarray:
    return np.array(t.matrix, dtype=np.float64).reshape(4, 4, -1)[..., 0]


def look(origin, forward) -> np.ndarray:
    """A camera at `origin` looking along `forward`, up +y: image right is forward x up."""
    o = np.asarray(origin, dtype=float)
    return matrix(T().look_at(origin=o.tolist(), target=(o + forward).tolist(), up=[0, 1, 0]))


def camera(to_world, **extra) -> dict:
    return {"type": "perspective", "fov": FOV, "to_world": T(to_world),
            "film": {"type": "hdrfilm", "width": W, "height": H}, **extra}


def scene(to_world, **shapes):
    return mi.load_dict({"type": "scene", "sensor": camera(to_world), **shapes})


def wall(z=0.0, size=50.0) -> dict:
    """A square facing +z at height z, wide enough to fill every view below."""
    return {"type": "rectangle", "to_world": T().translate([0, 0, z]).scale(size)}


def centres():
    """Each pixel's centre, (x right, y up) in pixels from the image centre, H x W each."""
    x = np.arange(W) + 0.5 - W / 2
    y = H / 2 - (np.arange(H) + 0.5)
    return np.meshgrid(x, y)


def rotated_y(v, degrees):
    t = math.radians(degrees)
    c, s = math.cos(t), math.sin(t)
    return np.array([c * v[0] + s * v[2], v[1], -s * v[0] + c * v[2]])


def test_names_are_parsed_in_order_and_bad_ones_refused():
    assert parse_passes("vector, depth") == ("depth", "vector")
    assert parse_passes(["Normal", "normal"]) == ("normal",)
    assert parse_passes(None) == () and parse_passes("") == ()
    with pytest.raises(UsageError) as info:
        parse_passes("depth,zdepth", "--passes")
    assert str(info.value) == ("bad value 'zdepth' for --passes: expected a comma-separated list "
                               "of depth, normal, vector, position, uv, mist, object_index, "
                               "material_index, albedo, emission, crypto_object, "
                               "crypto_material")
    with pytest.raises(UsageError, match="bad value 3 for passes"):
        parse_passes([3])


def test_a_sideways_camera_moves_every_pixel_of_a_wall_by_its_parallax():
    """The camera 10 above a wall moves by (0.3, -0.2) between frames: every point of the wall
    moves by f * (0.3, -0.2) / 10 pixels on the film, the other way round; in Blender's
    convention (previous - now, now - next, y up) that is +f * 0.3 / 10 and -f * 0.2 / 10."""
    d, s, t = 10.0, 0.3, -0.2
    down = np.array([0.0, 0.0, -1.0])
    sc = scene(look([0, 0, d], down), w=wall())
    motion = Motion(previous=look([-s, -t, d], down), next=look([s, t, d], down))
    v = render_data_passes(sc, ["vector"], spp=4, seed=3, motion=motion)["vector"]
    expected = np.array([F * s / d, F * t / d, F * s / d, F * t / d])
    print(f"expected {expected}, got {v.reshape(-1, 4).min(0)} .. {v.reshape(-1, 4).max(0)}")
    np.testing.assert_allclose(v.reshape(-1, 4), np.tile(expected, (W * H, 1)), atol=1e-3)


def test_a_turning_camera_moves_the_wall_as_its_pinhole_says():
    """The camera turns 3 degrees about its up axis each frame in front of a wall that fills the
    view: each pixel's vector is where its centre's wall point lands in the other frames' images
    (pinhole projection written here), to within the spread of the pixel's 64 samples."""
    d, turn = 6.0, 3.0
    c = np.array([0.0, 0.0, d])
    forward = np.array([0.0, 0.0, -1.0])
    sc = scene(look(c, forward), w=wall())
    motion = Motion(previous=look(c, rotated_y(forward, -turn)),
                    next=look(c, rotated_y(forward, turn)))
    v = render_data_passes(sc, ["vector"], spp=64, seed=1, motion=motion)["vector"]
    x, y = centres()
    right, up = np.array([1.0, 0, 0]), np.array([0, 1.0, 0])
    rays = x[..., None] / F * right + y[..., None] / F * up + forward
    points = c + rays * (d / -rays[..., 2:3])  # on the wall z = 0

    def pixel(degrees):
        fwd, rt = rotated_y(forward, degrees), rotated_y(right, degrees)
        rel = points - c
        depth = rel @ fwd
        return F * (rel @ rt) / depth, F * (rel @ up) / depth

    (xp, yp), (xn, yn) = pixel(-turn), pixel(turn)
    expected = np.stack([xp - x, yp - y, x - xn, y - yn], -1)
    err = np.abs(v - expected).max()
    print(f"largest vector {np.abs(expected).max():.3f} px, largest error {err:.5f} px")
    assert np.abs(expected[..., 0]).min() > 1.0  # the turn moves every pixel
    assert err < 0.01


@pytest.mark.parametrize("instanced", [False, True])
def test_a_moving_object_moves_over_a_still_background(instanced):
    """A square 2 above the wall moves by (0.4, 0.25) per frame; the camera stands still. Pixels
    that see only the square move by f * (0.4, 0.25) / 8 (towards where it was: negative), pixels
    that see only the wall do not move; also where the square is an instance of a shape group."""
    d, z, half = 10.0, 2.0, 1.5
    step = np.array([0.4, 0.25, 0.0])
    square = {"type": "rectangle", "to_world": T().translate([0, 0, z]).scale(half)}
    cam = look([0, 0, d], np.array([0.0, 0.0, -1.0]))
    if instanced:
        shapes = {"group": {"type": "shapegroup", "s": {"type": "rectangle"}},
                  "thing": {"type": "instance", "shapegroup": {"type": "ref", "id": "group"},
                            "to_world": T().translate([0, 0, z]).scale(half)}}
    else:
        shapes = {"thing": square}
    sc = scene(cam, w=wall(), **shapes)
    thing = next(s for s in sc.shapes() if s.id() == "thing")
    motion = Motion(cam, cam, ((thing, matrix(T().translate((-step).tolist())),
                                matrix(T().translate(step.tolist()))),))
    v = render_data_passes(sc, ["vector"], spp=4, seed=2, motion=motion)["vector"]
    # each pixel's corners in the square's plane: inside it all, or outside it all
    xs = (np.arange(W + 1) - W / 2) * (d - z) / F
    ys = (H / 2 - np.arange(H + 1)) * (d - z) / F
    inside = (np.abs(xs)[None, :] < half) & (np.abs(ys)[:, None] < half)
    corners = np.stack([inside[:-1, :-1], inside[1:, :-1], inside[:-1, 1:], inside[1:, 1:]])
    on, off = corners.all(0), ~corners.any(0)
    shift = F * step[:2] / (d - z)
    print(f"{on.sum()} pixels on the square, {off.sum()} off it; expected {-shift}")
    assert on.sum() > 20 and off.sum() > 200
    np.testing.assert_allclose(v[on], np.tile([*-shift, *-shift], (on.sum(), 1)), atol=1e-3)
    assert np.abs(v[off]).max() == 0.0


def test_depth_on_a_tilted_plane_and_its_normal():
    """A plane through the origin tilted 35 degrees about x, the camera 5 above it looking down:
    each pixel's depth (its first sample's distance along the view axis) lies between the plane's
    depths at the pixel's corners, and its normal is the plane's, towards the camera, also where
    the plane is seen from its back."""
    d, tilt = 5.0, 35.0
    n = np.array([0.0, -math.sin(math.radians(tilt)), math.cos(math.radians(tilt))])
    cam = look([0, 0, d], np.array([0.0, 0.0, -1.0]))
    xs, ys = np.arange(W + 1) - W / 2, H / 2 - np.arange(H + 1)
    gx, gy = np.meshgrid(xs, ys)
    # the ray (x / F, y / F, -1) from (0, 0, d) meets n.p = 0 at depth t: n.c + t n.ray = 0
    corner_depth = -n[2] * d / (n[0] * gx / F + n[1] * gy / F - n[2])
    c4 = np.stack([corner_depth[:-1, :-1], corner_depth[1:, :-1], corner_depth[:-1, 1:],
                   corner_depth[1:, 1:]])
    for back in (False, True):
        flip = T().rotate([1, 0, 0], 180.0) if back else T()
        plane = {"type": "rectangle",
                 "to_world": T().rotate([1, 0, 0], tilt) @ flip @ T().scale(100.0)}
        out = render_data_passes(scene(cam, p=plane), ALL, spp=8, seed=4)
        depth, normal = out["depth"], out["normal"]
        print(f"back={back}: depth {depth.min():.4f} .. {depth.max():.4f}")
        assert (depth >= c4.min(0) - 1e-4).all() and (depth <= c4.max(0) + 1e-4).all()
        assert depth.max() - depth.min() > 1.0  # the tilt shows
        np.testing.assert_allclose(normal.reshape(-1, 3), np.tile(n, (W * H, 1)), atol=1e-5)
        assert np.abs(out["vector"]).max() == 0.0  # a still


def test_background_pixels_and_edges():
    """A small square in the middle of nothing: outside it Depth is Cycles' 1e10 and Normal and
    Vector 0; on its edge the normal is shortened by the share of samples that missed."""
    cam = look([0, 0, 10.0], np.array([0.0, 0.0, -1.0]))
    sc = scene(cam, s={"type": "rectangle", "to_world": T().scale(1.1)})
    moving = Motion(look([0.5, 0, 10.0], np.array([0.0, 0.0, -1.0])), cam)
    out = render_data_passes(sc, ALL, spp=16, seed=5, motion=moving)
    depth, normal, vector = out["depth"], out["normal"], out["vector"]
    corner = (slice(0, 3), slice(0, 3))
    assert (depth[corner] == BACKGROUND_DEPTH).all()
    assert (normal[corner] == 0).all() and (vector[corner] == 0).all()
    lengths = normal[..., 2]
    edge = (lengths > 0) & (lengths < 1)
    print(f"{edge.sum()} edge pixels")
    assert edge.sum() > 4
    # the camera moved, the square did not: its pixels all move alike, edge pixels too (the
    # vector is averaged over the samples that hit)
    hit = lengths > 0
    np.testing.assert_allclose(vector[hit][:, 0], -F * 0.5 / 10.0, atol=1e-3)


def test_the_passes_do_not_depend_on_the_launch_size():
    cam = look([0, 0, 10.0], np.array([0.0, 0.0, -1.0]))
    sc = scene(cam, s={"type": "sphere", "radius": 2.0})
    motion = Motion(look([0.3, 0, 10.0], np.array([0.0, 0.0, -1.0])), cam)
    one = render_data_passes(sc, ALL, spp=3, seed=9, motion=motion)
    cut = render_data_passes(sc, ALL, spp=3, seed=9, motion=motion, lanes=100)
    for key in ALL:
        assert np.array_equal(one[key], cut[key]), key
    other = render_data_passes(sc, ["normal"], spp=3, seed=10)
    assert not np.array_equal(one["normal"], other["normal"])  # the seed moves the jitter


@pytest.mark.parametrize("kind", ["offset", "thinlens"])
def test_the_view_projects_as_mitsubas_own_camera(kind):
    """`View.pixels` of points in front of the camera equals the film position Mitsuba's sensor
    gives them (`sample_direction`, which light tracing uses)."""
    cam = look([0.2, -0.1, 4.0], np.array([0.1, 0.05, -1.0]))
    extra = ({"principal_point_offset_x": 0.1, "principal_point_offset_y": -0.2}
             if kind == "offset" else {})
    desc = camera(cam, **extra)
    if kind == "thinlens":
        desc.update(type="thinlens", aperture_radius=0.05, focus_distance=4.0)
    sensor = mi.load_dict(desc)
    rng = np.random.default_rng(0)
    points = np.stack([rng.uniform(-1, 1, 50), rng.uniform(-0.7, 0.7, 50),
                       rng.uniform(-1, 1, 50)], -1)
    mine, front = View.of(sensor).pixels(points)
    it = mi.Interaction3f()
    it.p = mi.Point3f(*points.T)
    ds, _ = sensor.sample_direction(it, mi.Point2f(0.5, 0.5))
    theirs = np.array(ds.uv, dtype=np.float64).reshape(2, -1).T
    seen = np.array(ds.pdf) > 0
    assert front.all() and seen.sum() > 30
    np.testing.assert_allclose(mine[seen], theirs[seen], atol=2e-3)


def test_an_orthographic_camera_moves_by_its_scale():
    """An orthographic camera whose film spans 2 * 3 world units sideways moves by 0.3: each
    point moves by 0.3 * W / 6 pixels, whatever its depth."""
    cam = look([0, 0, 10.0], np.array([0.0, 0.0, -1.0])) @ matrix(T().scale([3.0, 3.0, 1.0]))
    sc = mi.load_dict({"type": "scene", "w": wall(), "b": {"type": "sphere", "radius": 1.0},
                       "sensor": {"type": "orthographic", "to_world": T(cam),
                                  "film": {"type": "hdrfilm", "width": W, "height": H}}})
    before = matrix(T().translate([-0.3, 0, 0])) @ cam
    v = render_data_passes(sc, ["vector"], spp=2, seed=0, motion=Motion(before, cam))["vector"]
    np.testing.assert_allclose(v[..., 0], 0.3 * W / 6.0, atol=1e-3)
    assert np.abs(v[..., 1:]).max() < 1e-3


def test_a_camera_no_pixel_map_projects_is_refused_in_one_line():
    sc = mi.load_dict({"type": "scene", "w": wall(),
                       "sensor": {"type": "radiancemeter", "origin": [0, 0, 5.0],
                                  "direction": [0, 0, -1.0],
                                  "film": {"type": "hdrfilm", "width": 1, "height": 1}}})
    assert render_data_passes(sc, ["depth"], spp=2)["depth"][0, 0] == pytest.approx(5.0)
    with pytest.raises(SceneError) as info:
        render_data_passes(sc, ["vector"], spp=2)
    print(info.value)
    assert "vector pass needs a pinhole, thin lens or orthographic camera" in str(info.value)
    assert "\n" not in str(info.value)
