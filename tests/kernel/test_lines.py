"""Feature lines (kernel/lines.py) against answers from geometry.

The scenes are black (diffuse reflectance 0) with no light and white lines, so a pixel's value is
the fraction of its camera samples that found a line. Where a test says "no line" it means exactly
0: the geometry is exact and no sample can fire there unless detection is wrong (there is no noise
to allow for).
"""
import math

import numpy as np
import pytest

import styletrace
from styletrace.config import settings
from styletrace.config.settings import parse_lines
from styletrace.errors import SettingsError
from styletrace.gate import dr, mi
from styletrace.kernel.lane_sampler import LaneSampler
from styletrace.kernel.lines import Lines

T = mi.ScalarTransform4f
FOV = 40.0
BLACK = {"type": "diffuse", "reflectance": {"type": "rgb", "value": [0.0, 0.0, 0.0]}}
WHITE_LINES = {"lines": True, "line_color": "1,1,1"}


def camera(origin, target, res, up=(0, 1, 0)):
    return {"type": "perspective", "fov": FOV, "fov_axis": "smaller",
            "to_world": T().look_at(origin=origin, target=target, up=up),
            "sampler": {"type": "independent", "sample_count": 4},
            "film": {"type": "hdrfilm", "width": res, "height": res, "rfilter": {"type": "box"},
                     "pixel_format": "rgb", "component_format": "float32"}}


def focal(res):
    """Pixels per unit of tan(angle) for the pinhole above."""
    return 0.5 * res / math.tan(math.radians(0.5 * FOV))


def render(scene, spp=4, **values):
    return styletrace.render(scene, spp=spp, **{**WHITE_LINES, **values})[..., 0]


def ring_distance(res, center, radius):
    """For each pixel: (nearest, farthest) distance of its square from `center`, and the distance
    of its square from the circle of `radius` (0 where the circle crosses it)."""
    y, x = np.mgrid[0:res, 0:res].astype(float)
    dx = np.maximum(np.maximum(x - center[0], center[0] - (x + 1)), 0.0)
    dy = np.maximum(np.maximum(y - center[1], center[1] - (y + 1)), 0.0)
    near = np.hypot(dx, dy)
    far = np.hypot(np.maximum(abs(x - center[0]), abs(x + 1 - center[0])),
                   np.maximum(abs(y - center[1]), abs(y + 1 - center[1])))
    gap = np.where(near > radius, near - radius, np.where(far < radius, radius - far, 0.0))
    return gap


# ---- a sphere against a plane --------------------------------------------------------------------
def sphere_scene(res, dist=4.0, radius=1.0):
    return {
        "type": "scene",
        "sensor": camera([0, 0, dist], [0, 0, 0], res),
        "sphere": {"type": "sphere", "radius": radius, "bsdf": BLACK},
        "plane": {
            "type": "rectangle",
            "to_world": T().translate([0, 0, -1.5]) @ T().scale(6.0),
            "bsdf": BLACK,
        },
    }


def sphere_outline(res, dist=4.0, radius=1.0):
    """The analytic image-space outline of the sphere: a circle about the image centre."""
    return focal(res) * math.tan(math.asin(radius / dist))


def test_sphere_silhouette_is_covered_and_interiors_are_clean():
    res, width = 64, 2.0
    img = render(sphere_scene(res), line_width=width)
    gap = ring_distance(res, (res / 2, res / 2), sphere_outline(res))
    on = gap == 0.0                       # pixels the outline crosses
    assert on.sum() > 100
    assert (img[on] > 0).mean() >= 0.9
    # no sample there lies within the stencil's reach of the outline
    off = gap > 0.5 * width + 0.5
    assert img[off].max() == 0.0
    assert off.sum() > 0.8 * res * res


def ortho_camera(res, half_width):
    """An orthographic sensor looking down -z that sees [-half_width, half_width]^2 (Mitsuba maps
    the film to [-1, 1]^2 before `to_world`'s scale)."""
    cam = camera([0, 0, 4], [0, 0, 0], res)
    cam["type"] = "orthographic"
    del cam["fov"], cam["fov_axis"]
    cam["to_world"] = cam["to_world"] @ T().scale([half_width, half_width, 1.0])
    return cam


@pytest.mark.parametrize("line_depth", [1, 2])
def test_orthographic_silhouette_is_covered_and_interiors_are_clean(line_depth):
    """An orthographic camera has parallel rays: its pixel beam has a fixed width (the origin
    differential) and no angle. The depth test once measured the beam by its angle alone (radius
    0), so every rounding error between two points of one flat plane fired and the image was all
    line. The outline is the sphere's radius over the pixel size, res / 4 pixels; away from it
    nothing may fire."""
    res, width = 64, 2.0
    scene = sphere_scene(res)
    scene["sensor"] = ortho_camera(res, 2.0)
    img = render(scene, line_width=width, line_depth=line_depth)
    gap = ring_distance(res, (res / 2, res / 2), res / 4)
    on = gap == 0.0
    assert on.sum() > 100
    assert (img[on] > 0).mean() >= 0.9
    off = gap > 0.5 * width + 0.5
    assert img[off].max() == 0.0, (img[off] > 0).mean()


def test_orthographic_reflected_silhouette_keeps_its_screen_width():
    """Past a flat mirror an orthographic beam stays parallel and as wide: the stencil of the
    second edge must offset its origins by the beam's width (with the angle alone, 0, every
    auxiliary ray was the base ray and the mirror showed no line). The mirrored sphere's outline
    has the direct one's line mass."""
    res, radius = 64, 1.0
    mirror = {
        "type": "rectangle",
        "to_world": T().translate([0, 0, -5]) @ T().rotate([0, 1, 0], 45.0) @ T().scale(8.0),
        "bsdf": {"type": "conductor", "material": "none"},
    }
    cam = ortho_camera(res, 2.0)
    cam["to_world"] = T().look_at(origin=[0, 0, 0], target=[0, 0, -1], up=[0, 1, 0]) @ T().scale(
        [2.0, 2.0, 1.0]
    )
    reflected = {
        "type": "scene",
        "sensor": cam,
        "mirror": mirror,
        "sphere": {"type": "sphere", "center": [3, 0, -5], "radius": radius, "bsdf": BLACK},
    }
    direct = {
        "type": "scene",
        "sensor": cam,
        "sphere": {"type": "sphere", "center": [0, 0, -8], "radius": radius, "bsdf": BLACK},
    }
    perimeter = 2 * math.pi * res / 4
    seen = render(direct, spp=8, line_depth=2).sum() / perimeter
    mirrored = render(reflected, spp=8, line_depth=2).sum() / perimeter
    assert 1.0 < seen < 3.0
    assert abs(mirrored / seen - 1.0) <= 0.3, (seen, mirrored)


@pytest.mark.parametrize("medium", [False, True])
def test_a_null_surface_draws_no_line(medium):
    """A cube with a `null` BSDF around the sphere (a participating medium's boundary, here with
    or without the medium) is invisible: its outline must not be drawn, and the sphere's outline
    behind it still is. The stencil's rays once stopped at the null surface and drew the box."""
    res, width, dist = 64, 2.0, 8.0
    scene = sphere_scene(res, dist=dist)
    # the cube's outline lies well inside the image (its front face spans 2 x 10 of the 2 x 20
    # degrees)
    scene["box"] = {"type": "cube", "to_world": T().scale(1.2), "bsdf": {"type": "null"}}
    if medium:  # thin: the sphere behind it stays visible, and the walk is volpath's
        scene["box"]["interior"] = {"type": "homogeneous", "sigma_t": 0.05, "albedo": 0.5}
    img = render(scene, line_width=width, line_depth=1)
    gap = ring_distance(res, (res / 2, res / 2), sphere_outline(res, dist=dist))
    on = gap == 0.0
    assert (img[on] > 0).mean() >= 0.9
    off = gap > 0.5 * width + 0.5
    assert img[off].max() == 0.0, (img[off] > 0).mean()


def test_lines_off_is_the_image_without_the_property(monkeypatch):
    """Off, no line code is traced at all (a Python switch): the kernels are those of a build
    without lines."""
    from styletrace.kernel import lines

    def refuse(*args, **kwargs):
        raise AssertionError("line code traced with lines off")

    scene = sphere_scene(16)
    with monkeypatch.context() as m:
        m.setattr(lines.Lines, "__init__", refuse)
        styletrace.render(
            scene, spp=1, lines=False, stylize="first_n_hits", stylize_depth=2, inner=(1, 1)
        )
    plain = styletrace.render(scene, spp=2, seed=3)
    off = styletrace.render(scene, spp=2, seed=3, lines=False, line_width=3, line_samples=2)
    assert np.array_equal(plain, off)
    on = styletrace.render(scene, spp=2, seed=3, **WHITE_LINES)
    assert not np.array_equal(plain, on)


def test_gradient_colours_a_line_by_the_world_y_of_its_point():
    """line_gradient black -> white over y in [-1, 1]: a line pixel's colour is (y + 1) / 2 at
    the sphere's outline point it shows (the nearer hit of the pair: the sphere, not the plane).
    Same seed with a white constant colour gives the coverage, so the ratio of the two renders is
    the colour alone."""
    res, dist, radius = 48, 4.0, 1.0
    scene = sphere_scene(res, dist, radius)
    shade = render(scene, seed=2, line_gradient="0,0,0;1,1,1;-1;1")
    cover = render(scene, seed=2)
    line = cover > 0.25
    y_px = (np.mgrid[0:res, 0:res][0] + 0.5 - res / 2)
    # the outline circle: the sphere's points where the view ray grazes it lie at height (sin of the
    # image angle) x radius x sqrt(1 - (radius/dist)^2), on the circle of radius `outline` pixels
    outline = sphere_outline(res, dist, radius)
    x_px = (np.mgrid[0:res, 0:res][1] + 0.5 - res / 2)
    y_world = -y_px / np.hypot(x_px, y_px).clip(1e-9) * radius * math.sqrt(1 - (radius / dist) ** 2)
    near = line & (abs(np.hypot(x_px, y_px) - outline) < 1.0)
    assert near.sum() > 50
    err = abs(shade[near] / cover[near] - (y_world[near] + 1) / 2)
    # a pixel spans 0.07 in y here, its samples' points differ by that much
    assert err.max() < 0.08


def test_line_objects_choose_the_shapes_that_draw():
    res = 48
    scene = {"type": "scene", "sensor": camera([0, 0, 4], [0, 0, 0], res),
             "left": {"type": "sphere", "center": [-0.8, 0, 0], "radius": 0.5, "bsdf": BLACK},
             "right": {"type": "sphere", "center": [0.8, 0, 0], "radius": 0.5, "bsdf": BLACK}}
    both = render(scene)
    only = render(scene, line_objects="left")
    assert both[:, : res // 2].max() > 0 and both[:, res // 2:].max() > 0
    assert only[:, : res // 2].max() > 0 and only[:, res // 2:].max() == 0.0
    from styletrace.errors import SceneError

    with pytest.raises(
        SceneError,
        match="bad value 'middle' in 'line_objects': the scene's shape ids are left, right",
    ):
        render(scene, line_objects="left,middle")


# ---- a flat mirror -------------------------------------------------------------------------------
@pytest.mark.parametrize(
    "mode",
    [{}, {"stylize": "first_n_hits", "stylize_depth": 2}, {"stylize": "first_object_hit"}],
    ids=["first_hit", "first_n_hits", "first_object_hit"],
)
def test_a_reflected_silhouette_keeps_its_screen_width(mode):
    """The camera looks down -z at a mirror tilted 45 degrees that shows a sphere 3 units to its
    side: the sphere's mirror image sits where a sphere 8 units in front of the camera would. The
    same sphere seen directly at 8 units draws the same outline; the line mass per pixel of
    outline is the line's width."""
    res, radius = 64, 1.0
    mirror = {
        "type": "rectangle",
        "to_world": T().translate([0, 0, -5]) @ T().rotate([0, 1, 0], 45.0) @ T().scale(8.0),
        "bsdf": {"type": "conductor", "material": "none"},
    }
    reflected = {
        "type": "scene",
        "sensor": camera([0, 0, 0], [0, 0, -1], res),
        "mirror": mirror,
        "sphere": {"type": "sphere", "center": [3, 0, -5], "radius": radius, "bsdf": BLACK},
    }
    direct = {"type": "scene", "sensor": camera([0, 0, 0], [0, 0, -1], res),
              "sphere": {"type": "sphere", "center": [0, 0, -8], "radius": radius, "bsdf": BLACK}}
    perimeter = 2 * math.pi * sphere_outline(res, 8.0, radius)
    seen = render(direct, spp=8, line_depth=2).sum() / perimeter
    mirrored = render(reflected, spp=8, line_depth=2, **mode).sum() / perimeter
    assert 1.0 < seen < 3.0                       # about line_width (2) pixels
    assert abs(mirrored / seen - 1.0) <= 0.3
    # with line_depth 1 only the camera ray is tested: the mirror shows no line
    assert render(reflected, spp=2, line_depth=1, **mode).max() == 0.0


# ---- a cube: creases -----------------------------------------------------------------------------
def project(points, origin, target, res):
    """World points -> pixel coordinates for `camera(origin, target, res)` (Mitsuba's look_at frame:
    image x grows against the frame's 'left', image y against its 'up')."""
    origin, target = np.asarray(origin, float), np.asarray(target, float)
    forward = (target - origin) / np.linalg.norm(target - origin)
    left = np.cross([0.0, 1.0, 0.0], forward)
    left /= np.linalg.norm(left)
    up = np.cross(forward, left)
    rel = np.asarray(points, float) - origin
    z = rel @ forward
    return np.stack(
        [res / 2 - focal(res) * (rel @ left) / z, res / 2 - focal(res) * (rel @ up) / z], axis=-1
    )


def segment_distance(px, a, b):
    ab = b - a
    t = np.clip(((px - a) @ ab) / (ab @ ab), 0.0, 1.0)
    return np.linalg.norm(px - (a + t[..., None] * ab), axis=-1)


def test_cube_edges_come_from_the_crease_test():
    res, eye = 64, [3.2, 2.6, 3.8]
    scene = {
        "type": "scene",
        "sensor": camera(eye, [0, 0, 0], res),
        "cube": {"type": "cube", "bsdf": BLACK},
    }
    img = render(scene, line_tests="crease")
    y, x = np.mgrid[0:res, 0:res]
    centres = np.stack([x + 0.5, y + 0.5], axis=-1).astype(float)
    corners = np.array([[i, j, k] for i in (-1, 1) for j in (-1, 1) for k in (-1, 1)], float)
    edges = [
        (a, b) for a in range(8) for b in range(a + 1, 8) if np.sum(corners[a] != corners[b]) == 1
    ]
    pix = project(corners, eye, [0, 0, 0], res)
    dist = np.min([segment_distance(centres, pix[a], pix[b]) for a, b in edges], axis=0)
    # the three edges meeting at the corner that faces the camera are creases between visible faces
    near = 7  # corner (1, 1, 1)
    inner = [(a, b) for a, b in edges if near in (a, b)]
    d_inner = np.min([segment_distance(centres, pix[a], pix[b]) for a, b in inner], axis=0)
    far_from_ends = (
        np.min(np.linalg.norm(centres[:, :, None, :] - pix[None, None], axis=-1), axis=-1) > 3
    )
    on = (d_inner < 0.5) & far_from_ends
    assert on.sum() > 30
    assert (img[on] > 0).mean() >= 0.9
    # the faces' insides: rays that hit the cube (slab test), far from every edge
    origin = np.asarray(eye, float)
    fwd = -origin / np.linalg.norm(origin)
    left = np.cross([0, 1, 0], fwd)
    left /= np.linalg.norm(left)
    up = np.cross(fwd, left)
    dirs = fwd + ((res / 2 - centres[..., :1]) * left + (res / 2 - centres[..., 1:]) * up) / focal(
        res
    )
    with np.errstate(divide="ignore"):
        t1, t2 = (-1 - origin) / dirs, (1 - origin) / dirs
    hits = np.max(np.minimum(t1, t2), axis=-1) < np.min(np.maximum(t1, t2), axis=-1)
    inside = hits & (dist > 2.0)
    assert inside.sum() > 300
    assert img[inside].max() == 0.0
    # the outline against nothing is no crease: with the crease test alone it stays dark
    outline = ~hits & (dist > 1.5)
    assert img[outline].max() == 0.0


# ---- a tessellated plane in two meshes -----------------------------------------------------------
def grid_obj(path, x0, x1, flip, n=6):
    """A tessellated patch of the plane y = 0 over x in [x0, x1], z in [-2, 2] (winding flipped: its
    normals point down)."""
    xs, zs = np.linspace(x0, x1, n + 1), np.linspace(-2, 2, n + 1)
    lines = [f"v {x} 0 {z}" for z in zs for x in xs]
    for j in range(n):
        for i in range(n):
            a, b, c, d = (
                j * (n + 1) + i + 1,
                j * (n + 1) + i + 2,
                (j + 1) * (n + 1) + i + 2,
                (j + 1) * (n + 1) + i + 1,
            )
            tris = [(a, d, c), (a, c, b)]
            lines += [
                f"f {t[2]} {t[1]} {t[0]}" if flip else f"f {t[0]} {t[1]} {t[2]}" for t in tris
            ]
    path.write_text("\n".join(lines) + "\n")
    return str(path)


def test_no_false_lines_at_a_seam_between_meshes(tmp_path):
    """Two tessellated meshes of one plane meet along a seam, the right one with flipped normals,
    seen at a slant (up to 80 degrees from the normal): crease, depth, albedo and silhouette
    tests stay silent there. Their BSDFs differ (else Mitsuba merges the meshes into one shape),
    so the boundary test alone draws the seam, as it should."""
    res = 48
    left, right = (
        grid_obj(tmp_path / "left.obj", -2, 0, False),
        grid_obj(tmp_path / "right.obj", 0, 2, True),
    )
    tilt = T().rotate([1, 0, 0], -62.0) @ T().rotate([1, 0, 0], 90.0)
    other = {"type": "diffuse", "reflectance": {"type": "rgb", "value": [0.0, 0.0, 0.01]}}
    scene = {"type": "scene", "sensor": camera([0, 0, 2.2], [0, 0, 0], res),
             "left": {"type": "obj", "filename": left, "to_world": tilt, "bsdf": BLACK},
             "right": {"type": "obj", "filename": right, "to_world": tilt, "bsdf": other}}
    assert len(mi.load_dict(scene).shapes()) == 2
    below = slice(res // 4 + 2, res - 2)   # the patch's far border (a silhouette) lies above
    img = render(scene, line_tests="silhouette,crease,albedo,depth")
    assert img[below].max() == 0.0
    seam = render(scene, line_tests="boundary")[below]
    assert (seam[:, res // 2 - 1: res // 2 + 1].max(axis=1) > 0).all()


# ---- a thin rod ----------------------------------------------------------------------------------
def test_a_thin_rod_is_detected():
    res, dist = 48, 4.0
    pixel = math.tan(math.radians(FOV / 2)) * dist / (res / 2)  # a pixel's size at the rod
    rod = {
        "type": "cylinder",
        "p0": [0, -3, 0],
        "p1": [0, 3, 0],
        "radius": 0.3 * pixel,
        "bsdf": BLACK,
    }
    scene = {
        "type": "scene",
        "sensor": camera([0, 0, dist], [0, 0, 0], res),
        "rod": rod,
        "plane": {
            "type": "rectangle",
            "to_world": T().translate([0, 0, -1.0]) @ T().scale(6.0),
            "bsdf": BLACK,
        },
    }
    img = render(scene)
    column = img[:, res // 2 - 2: res // 2 + 2]
    assert (column.max(axis=1) > 0).mean() >= 0.9   # each row finds the rod, 0.6 pixels wide
    assert img[:, : res // 2 - 3].max() == 0.0 and img[:, res // 2 + 3:].max() == 0.0


# ---- coverage against N --------------------------------------------------------------------------
def straddling_rays(m, delta, pixel=0.002):
    """A wall whose edge x = 0 lies `delta` pixels left of m identical camera rays (pixel: 0.002
    rad)."""
    scene = mi.load_dict({"type": "scene", "wall": {"type": "rectangle", "bsdf": BLACK,
                                                     "to_world": T().translate([-1.0, 0, -5])}})
    x = delta * pixel * 5.0
    zero, one = dr.zeros(mi.Float, m), dr.full(mi.Float, 1.0, m)
    ray = mi.RayDifferential3f(
        mi.Point3f(zero, zero, zero), dr.normalize(mi.Vector3f(x * one, zero, -5.0 * one))
    )
    ray.o_x, ray.o_y = mi.Point3f(ray.o), mi.Point3f(ray.o)
    ray.d_x = dr.normalize(mi.Vector3f((x + pixel * 5.0) * one, zero, -5.0 * one))
    ray.d_y = dr.normalize(mi.Vector3f(x * one, pixel * 5.0 * one, -5.0 * one))
    ray.has_differentials = True
    return scene, ray


def fired_share(scene, ray, m, seed, **line):
    lines = Lines(parse_lines({"lines": True, **{f"line_{k}": v for k, v in line.items()}}), scene)
    rng = LaneSampler(mi.PCG32(m, initstate=seed, initseq=dr.arange(mi.UInt64, m)))
    seen, _ = lines.camera(scene, rng, ray, 1, mi.Bool(True))
    return float(np.mean(np.asarray(seen.fired)))


def segment_share(delta, r):
    """The share of a disc of radius r beyond a line at distance delta from its centre."""
    return (r * r * math.acos(delta / r) - delta * math.sqrt(r * r - delta * delta)) / (
        math.pi * r * r
    )


M, DELTA, WIDTH = 40000, 0.6, 2.0
#: perspective: the stencil is a disc of directions, not of parallel rays; measured shares differ
#: from the flat-disc formula by less than this
FLAT = 0.01


def test_coverage_rises_with_n_as_one_minus_one_minus_q_to_the_n():
    """Identical camera rays at a fixed distance delta from a straight outline: each auxiliary
    ray is an independent uniform point of the stencil disc, so P(line) = 1 - (1 - q)^N with q
    the disc's share beyond the outline (a circular segment)."""
    scene, ray = straddling_rays(M, DELTA)
    q_exact = segment_share(DELTA, WIDTH / 2)
    q = fired_share(scene, ray, M, 7, width=WIDTH, samples=1)
    assert abs(q - q_exact) < 4 * math.sqrt(q_exact * (1 - q_exact) / M) + FLAT
    for n in (2, 4, 8):
        want = 1 - (1 - q) ** n
        # binomial noise of p_N plus that of q carried through the curve
        sd = math.sqrt(want * (1 - want) / M + (n * (1 - q) ** (n - 1)) ** 2 * q * (1 - q) / M)
        assert abs(fired_share(scene, ray, M, 7 + n, width=WIDTH, samples=n) - want) < 4 * sd, n


def test_expectation_mode_weight_is_the_kth_power_of_the_pair_metric():
    """line_mode=expectation: a random pair of stencil points straddles the outline with
    probability 2 q (1 - q), so E[m] = 1 - 2 q (1 - q) and the product of k metric samples is 1
    with probability E[m]^k: the share of samples that become line colour is 1 - E[m]^k."""
    scene, ray = straddling_rays(M, DELTA)
    q = segment_share(DELTA, WIDTH / 2)
    p1 = fired_share(scene, ray, M, 3, width=WIDTH, mode="expectation", k=1)
    assert abs(p1 - 2 * q * (1 - q)) < 4 * math.sqrt(p1 * (1 - p1) / M) + 2 * FLAT
    for k in (3, 12):
        want = 1 - (1 - p1) ** k
        sd = math.sqrt(want * (1 - want) / M + (k * (1 - p1) ** (k - 1)) ** 2 * p1 * (1 - p1) / M)
        assert (
            abs(fired_share(scene, ray, M, 3 + k, width=WIDTH, mode="expectation", k=k) - want)
            < 4 * sd
        ), k


def test_expectation_mode_blends_line_colour_and_radiance():
    """g = (1 - w) c + w L per sample: two renders with the same seed and line colours 0 and (0,
    5, 0) differ by 5 x (share of samples where a pair fired) in green alone, the radiance part
    being the same; the share is 0 away from the sphere's outline and positive along it."""
    from styletrace.scene.builtin import furnace
    common = dict(spp=4, seed=5, style="identity", lines=True, line_mode="expectation", line_k=4)
    black = styletrace.render(furnace(32, 32), line_color="0,0,0", **common)
    green = styletrace.render(furnace(32, 32), line_color="0,5,0", **common)
    share = (green[..., 1] - black[..., 1]) / 5.0
    assert np.array_equal(green[..., 0], black[..., 0]) and np.array_equal(
        green[..., 2], black[..., 2]
    )
    assert share.min() >= -1e-6 and share.max() <= 1 + 1e-6
    gap = ring_distance(
        32,
        (16, 16),
        focal(32)
        * math.tan(math.asin(1 / 4.0))
        * math.tan(math.radians(20))
        / math.tan(math.radians(17.5)),
    )
    assert share[gap > 1.5].max() == 0.0 and share[gap == 0].mean() > 0.3


# ---- settings ------------------------------------------------------------------------------------
@pytest.mark.parametrize(
    "key,value,match",
    [
        ("line_width", "0", "line_width"),
        ("line_width", "wide", "line_width"),
        ("line_samples", 0, "line_samples"),
        ("line_depth", 0, "line_depth"),
        ("line_tests", "outline", "outline"),
        ("line_crease", 2, "line_crease"),
        ("line_color", "1,2", "line_color"),
        ("line_mode", "smooth", "line_mode"),
        ("line_k", 0, "line_k"),
        ("line_gradient", "1,1,1", "line_gradient"),
        ("lines", "maybe", "lines"),
    ],
)
def test_bad_line_values_get_one_line(key, value, match):
    with pytest.raises(SettingsError, match=match) as err:
        settings.parse({"lines": True, key: value})
    assert "\n" not in str(err.value)


def test_line_settings_parse():
    s = settings.parse(
        {
            "lines": "true",
            "line_width": "3",
            "line_gradient": "0,0,1;1,0,0;0;1",
            "line_tests": "crease",
        }
    )
    assert s.lines.width == 3.0 and s.lines.tests == ("crease",)
    assert s.lines.gradient == ((0.0, 0.0, 1.0), (1.0, 0.0, 0.0), 0.0, 1.0)
    assert settings.parse({}).lines is None
