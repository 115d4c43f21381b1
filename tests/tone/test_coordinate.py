"""The image coordinate itself: the MLS inverse and its fallback chain on known data, the
coordinate at a fixed world point seen in a glossy mirror (independent of roughness, and where
the point is seen in the perfect mirror), and halftone dots on a point behind the camera that
only a mirror shows."""
import numpy as np
import pytest
from helpers.pattern import peak

from styletrace.gate import dr, mi
from styletrace.kernel import mls
from styletrace.kernel.anchors import Tone, ToneState, combine
from tone.scenes import T, mirror_scene, render, sensor, styled

RNG = np.random.default_rng(7)


def invert(points, coords, valid, x=(0, 0, 0), d=(0, 0, -1), first=(-99.0, -99.0)):
    """mls.invert on one lane per row of `points` [lanes, candidates, 3]."""
    P = [mi.Point3f(*[np.ascontiguousarray(points[:, i, k]).astype(np.float32) for k in range(3)])
         for i in range(points.shape[1])]
    S = [
        (mi.Float(coords[:, i, 0].astype(np.float32)), mi.Float(coords[:, i, 1].astype(np.float32)))
        for i in range(points.shape[1])
    ]
    V = [mi.Bool(valid[:, i]) for i in range(points.shape[1])]
    n = points.shape[0]
    s, m = mls.invert(
        mi.Point3f(*[np.full(n, c, np.float32) for c in x]),
        mi.Vector3f(*[np.full(n, c, np.float32) for c in d]),
        P,
        S,
        V,
        mi.Point2f(np.full(n, first[0], np.float32), np.full(n, first[1], np.float32)),
    )
    return np.array(s).T, np.array(m)


def test_mls_recovers_an_affine_map_exactly():
    """Points on the chart plane (z = 0, the query at the origin, incoming direction -z) mapped
    by an affine map: linear MLS reproduces it at the query (to float32 rounding), whatever the
    weights."""
    lanes, k = 50, 9
    A = RNG.normal(size=(lanes, 2, 2)) * 30
    b = RNG.normal(size=(lanes, 2)) * 100
    q = RNG.uniform(-1, 1, size=(lanes, k, 2))
    pts = np.concatenate([q, np.zeros((lanes, k, 1))], axis=2)
    coords = np.einsum("lij,lkj->lki", A, q) + b[:, None, :]
    s, m = invert(pts, coords, np.ones((lanes, k), bool))
    # the chart's basis is some rotation of (x, y): the map is affine in it too
    assert np.all(m == mls.MLS)
    np.testing.assert_allclose(s, b, atol=1e-3 * np.abs(coords).max())


def test_fallback_chain():
    """Candidates all on one line: no affine fit; the nearest candidate's coordinate. None valid:
    `first`."""
    pts = np.zeros((2, 4, 3))
    pts[:, :, 0] = [[0.5, 1.0, 2.0, 3.0]] * 2          # collinear in the chart
    coords = np.stack([np.arange(4) * 10.0, np.zeros(4)], axis=1)[None].repeat(2, 0)
    valid = np.array([[True] * 4, [False] * 4])
    s, m = invert(pts, coords, valid)
    assert list(m) == [mls.NEAREST, mls.FIRST]
    np.testing.assert_allclose(s[0], [0.0, 0.0])
    np.testing.assert_allclose(s[1], [-99.0, -99.0])
    # an off-centre cluster: the weighted centroid farther than CENTRE sigma, so MLS would
    # extrapolate
    pts = np.array([[[4, 0, 0], [5, 0, 0], [4, 1, 0], [5, 1, 0]]], float)
    coords = pts[..., :2] * 7.0
    s, m = invert(pts, coords, np.ones((1, 4), bool))
    assert m[0] == mls.AFFINE
    np.testing.assert_allclose(s[0], [0.0, 0.0], atol=1e-3)


def query_in_flat_mirror(scene, film_xy):
    """The perfect-mirror path through screen pixels `film_xy` (pixels right/up of the centre,
    the Projection convention): camera ray -> mirror (plane through (1.5, 0, 0), normal (1, 0,
    1)/sqrt 2) -> the plane x = 4.5, by numpy geometry. Returns (points on the plane, reflected
    directions)."""
    tone = Tone(scene)
    uv = tone.film_uv(mi.Float(film_xy[:, 0]), mi.Float(film_xy[:, 1]))
    ray, _ = scene.sensors()[0].sample_ray(mi.Float(0.0), mi.Float(0.5), uv, mi.Point2f(0.5, 0.5))
    o, d = np.array(ray.o).T.astype(np.float64), np.array(ray.d).T.astype(np.float64)
    n = np.array([1.0, 0.0, 1.0]) / np.sqrt(2)
    t = ((np.array([1.5, 0, 0]) - o) @ n) / (d @ n)
    m = o + t[:, None] * d
    r = d - 2 * (d @ n)[:, None] * n
    t2 = (4.5 - m[:, 0]) / r[:, 0]
    return m + t2[:, None] * r, r


@pytest.mark.parametrize("offset", [(7.0, -5.0), (12.0, 8.0)])
def test_coordinate_at_a_world_point_is_the_same_for_every_roughness(offset):
    """A point x on the plane seen in the mirror from pixel s*: a glossy sample reaches x from a
    camera sample whose first edge is elsewhere (s0 = s* + offset). The coordinate of x is
    computed from anchors around s0 in scenes of GGX roughness 0.001 and 0.1: the two agree to
    float rounding (anchors reflect about the geometric normal, whatever the material) and both
    find s* within 0.25 px (the MLS inverse of the perfect mirror's map, which is projective, not
    affine, over the anchors' 54 px)."""
    # on the mirror
    s_true = np.stack([np.linspace(-50, -30, 12), np.linspace(-20, 20, 12)], axis=1)
    out = []
    for alpha in (0.001, 0.1):
        scene = mirror_scene(dict(style="coordinate"), alpha=alpha)
        x, r = query_in_flat_mirror(scene, s_true)
        ray = mi.Ray3f(
            mi.Point3f(*(x - r).T.astype(np.float32)), mi.Vector3f(*r.T.astype(np.float32))
        )
        si = scene.ray_intersect(ray)
        mirror = [s for s in scene.shapes() if s.id() == "reflector"][0]
        n = len(s_true)
        key = combine(mi.UInt32(2166136261), dr.reinterpret_array(mi.UInt32, mi.ShapePtr(mirror)))
        state = ToneState(key=dr.repeat(key, n) if dr.width(key) == 1 else key, bits=mi.UInt32(0),
                          delta=mi.Bool(False),
                          s0=mi.Point2f(*(s_true + np.array(offset)).T.astype(np.float32)))
        tone = Tone(scene)
        s, m = tone.coordinate(scene, si, ray, mi.UInt32(1), state, mi.Bool(True))
        assert np.all(np.array(si.is_valid()))
        out.append((np.array(s).T, np.array(m)))
    (s1, m1), (s2, m2) = out
    np.testing.assert_array_equal(m1, m2)
    np.testing.assert_allclose(s1, s2, atol=1e-4)
    assert np.all(m1 == mls.MLS)
    np.testing.assert_allclose(s1, s_true, atol=0.25)    # measured: 0.0045 px at most


def behind_camera_scene(lift):
    """A perfect mirror at z = -1 facing the camera (at z = 6) shows a halftoned plane at z = 9,
    behind the camera: the camera sees the plane only in the mirror. No light: the dots are the
    largest everywhere."""
    style = dict(style="halftone", spacing_px=8.0, max_radius_fraction=0.5, u_min=0.0, u_max=2.0,
                 inner_samples=1, lift=lift)
    return mi.load_dict(
        {
            "type": "scene",
            "sensor": sensor(96),
            "mirror": {
                "type": "rectangle",
                "bsdf": {"type": "conductor", "material": "none"},
                "to_world": T().translate([0, 0, -1]) @ T().scale(8),
            },
            "back": {
                "type": "rectangle",
                "bsdf": styled(style),
                "to_world": T().translate([0, 0, 9]) @ T().rotate([0, 1, 0], 180) @ T().scale(12),
            },
        }
    )


def test_point_behind_the_camera_gets_regular_dots():
    """Canonical: the back plane, seen in the mirror, gets the screen's dot grid: the spectrum
    peaks at 8 px (10%), no pixel is NaN. Position mode: its points lie behind the camera, their
    projection is meaningless (depth clamped): no 8 px grid."""
    img = render(behind_camera_scene("canonical"), spp=4)
    assert np.all(np.isfinite(img))
    dark = (img.mean(axis=2) < 0.5).astype(float)
    region = np.ones(dark.shape, bool)
    s, _, _ = peak(dark, region)
    assert abs(s / 8.0 - 1) < 0.10
    # dots of radius 2.83 px on an 8 px grid cover pi 2.83^2 / 64 = 39%
    assert 0.2 < dark.mean() < 0.5
    pos = render(behind_camera_scene("position"), spp=4)
    pdark = (pos.mean(axis=2) < 0.5).astype(float)
    sp, _, _ = peak(pdark, region)
    assert not abs(sp / 8.0 - 1) < 0.10 or not 0.2 < pdark.mean() < 0.5
