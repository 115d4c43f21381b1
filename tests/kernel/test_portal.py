"""Light portals (kernel/portal.py, kernel/portal_guide.py, kernel/spherical_rectangle.py): the
`portal` emitter emits nothing, next-event estimation never picks it, the environment sampled
through it has the density MIS reads and a density that integrates to one, renders through a
window converge to Mitsuba's `path` without a portal, and with less error at equal samples."""
import math

import numpy as np
import pytest
from helpers.stats import mean_threshold, mean_z, pixel_t_test
from helpers.window_room import WINDOW_Y, WINDOW_Z, T, portal_over_window, window_room

from styletrace.errors import SceneError
from styletrace.frontends import api
from styletrace.gate import dr, mi
from styletrace.kernel import spherical_rectangle
from styletrace.kernel.emitter_sampler import EmitterSampler, auto_mode
from styletrace.kernel.portal import PortalEmitter, is_portal
from styletrace.kernel.portal_guide import SHARE

#: z beyond which a mean is rejected: a two-sided 5.7e-7 per test, at most a few hundred tests
Z = 5.0


def uniforms(count: int, seed: int, dims: int) -> list:
    rng = mi.PCG32(count, initseq=dr.arange(mi.UInt64, count) + seed)
    return [rng.next_float32() for _ in range(dims)]


def interactions(p: np.ndarray) -> mi.Interaction3f:
    """Interactions at the points p (no normal: what sampling reads of a point is its position)."""
    it = dr.zeros(mi.Interaction3f, len(p))
    it.p = mi.Point3f(*(mi.Float(p[:, i].astype(np.float32)) for i in range(3)))
    return it


# ---- the emitter itself

def test_the_portal_emits_nothing():
    """Every method Mitsuba calls returns zero; no flag makes it an environment, a surface or a
    delta light; Mitsuba's scene does not take it for its environment."""
    scene = mi.load_dict(window_room(8))
    portal = next(e for e in scene.emitters() if is_portal(e))
    assert isinstance(portal, PortalEmitter) and portal.flags() == 0
    assert not is_portal(scene.environment())
    n = 64
    it = interactions(np.random.default_rng(0).uniform(-2, 2, size=(n, 3)))
    u = uniforms(n, 1, 4)
    ds, w = portal.sample_direction(it, mi.Point2f(u[0], u[1]))
    assert np.all(np.asarray(w) == 0) and np.all(np.asarray(ds.pdf) == 0)
    assert np.all(np.asarray(portal.pdf_direction(it, ds)) == 0)
    assert np.all(np.asarray(portal.eval_direction(it, ds)) == 0)
    si = dr.zeros(mi.SurfaceInteraction3f, n)
    si.wi = mi.Vector3f(0, 0, 1)
    assert np.all(np.asarray(portal.eval(si)) == 0)
    _, w = portal.sample_ray(0.0, u[2], mi.Point2f(u[0], u[1]), mi.Point2f(u[2], u[3]))
    assert np.all(np.asarray(w) == 0)
    ps, w = portal.sample_position(0.0, mi.Point2f(u[0], u[1]))
    assert np.all(np.asarray(w) == 0) and np.all(np.asarray(portal.pdf_position(ps)) == 0)


def test_what_the_portal_holds():
    """Centre, half edges, the normal into the room (the transformed +z) and the area of the
    window it covers."""
    scene = mi.load_dict({"type": "scene", "p": portal_over_window()})
    p = scene.emitters()[0]
    np.testing.assert_allclose(p.center, [-2.0, 1.4, 0.0], atol=1e-6)
    np.testing.assert_allclose(np.abs(p.edge_x), [0, 0, 0.6], atol=1e-6)
    np.testing.assert_allclose(p.edge_y, [0, 0.5, 0], atol=1e-6)
    np.testing.assert_allclose(p.normal, [1, 0, 0], atol=1e-6)  # into the room, +x
    assert p.area == pytest.approx(1.2 * 1.0)
    # a mirroring to_world flips the normal, as it flips a rectangle shape's
    mirrored = mi.load_dict({"type": "portal", "to_world": T().scale([1.0, 1.0, -1.0])})
    np.testing.assert_allclose(mirrored.normal, [0, 0, -1])


@pytest.mark.parametrize("to_world, words", [
    (T().scale([1.0, 0.0, 1.0]), "zero area"),
    (mi.ScalarTransform4f([[1, 0.5, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1]]),
     "parallelogram"),
])
def test_a_bad_portal_is_refused_in_one_line(to_world, words):
    with pytest.raises(SceneError, match=f"portal 'bad'.*{words}") as err:
        api.load_scene({"type": "scene", "bad": {"type": "portal", "to_world": to_world}})
    assert "\n" not in str(err.value)


def test_mitsubas_path_renders_the_same_with_a_portal():
    """Mitsuba's `path` picks the portal for some light samples and gets nothing from them: the
    image means and 4 x 4 blocks with and without it agree (K renders each side)."""
    k, res, spp = 10, 24, 128
    path = mi.load_dict({"type": "path"})
    sides = []
    for portal in (True, False):
        scene = mi.load_dict(window_room(res, "envmap", portal=portal))
        sides.append(np.stack([np.asarray(mi.render(scene, integrator=path, spp=spp,
                                                    seed=s + (0 if portal else 1000)))
                               for s in range(k)]))
    z = mean_z(*sides)
    assert np.all(np.abs(z) < mean_threshold(k)), z
    tmax, thr, frac = pixel_t_test(*sides, alpha=1e-3, block=4)
    assert tmax < thr, (tmax, thr, frac)


# ---- selection and densities

def portals_scene() -> dict:
    """The window room with two more portals and a lamp: a skylight portal facing down from the
    ceiling (over no hole: the densities do not look at the walls) and a larger portal just outside
    the window, parallel to the first, so that rays through the window cross two portals; a small
    lamp makes the environment one emitter of two."""
    d = window_room(8)
    d["skylight"] = {"type": "portal", "to_world": T().translate([0.5, 2.5, 0.5])
                     @ T().rotate([1, 0, 0], 90) @ T().scale([0.4, 0.3, 1.0])}
    d["outer"] = {"type": "portal", "to_world": T().translate([-2.3, 1.4, 0.0])
                  @ T().rotate([0, 1, 0], 90) @ T().scale([0.9, 0.7, 1.0])}
    d["lamp"] = {"type": "rectangle", "to_world": T().translate([1.0, 2.4, -1.0])
                 @ T().rotate([1, 0, 0], 90) @ T().scale(0.2),
                 "emitter": {"type": "area", "radiance": {"type": "rgb", "value": [5.0] * 3}}}
    return d


def test_portals_are_never_selected():
    scene = mi.load_dict(portals_scene())
    assert sum(is_portal(e) for e in scene.emitters()) == 3
    sampler = EmitterSampler(scene, "uniform")
    assert sampler.count == 2 and sampler.guide is not None
    assert sampler.probabilities == pytest.approx([0.5, 0.5])
    assert not any("Portal" in key[0] for key in sampler.keys)
    # `auto` counts the emitters without portals: one light and a portal is one emitter
    one = mi.load_dict(window_room(8, sampler="owen_sobol"))
    assert auto_mode(one) == "uniform"
    assert EmitterSampler(one).count == 1
    n = 1 << 12
    it = interactions(np.random.default_rng(2).uniform([-1.9, 0.1, -1.9], [1.9, 2.4, 1.9],
                                                        size=(n, 3)))
    u = uniforms(n, 3, 2)
    for mode in ("uniform", "spatial"):
        s = EmitterSampler(scene, mode)
        ds, _ = s.sample_direction(it, mi.Point2f(u[0], u[1]), mi.Bool(True), visible=False)
        picked = {id(e) for e in scene.emitters()
                  if np.any(np.asarray(ds.emitter == mi.EmitterPtr(e)))}
        assert picked == {id(e) for e in scene.emitters() if not is_portal(e)}


def test_scenes_listing_their_portals_differently_render_alike():
    """Mitsuba lists emitters in an order of its own; the portals are taken in a stable one, so
    the same seed gives the same image whichever order the scene dict (and Mitsuba) lists them."""
    d = portals_scene()
    listed = {"type": "scene", **{k: v for k, v in reversed(d.items()) if k != "type"}}
    images = []
    for desc in (d, listed):
        scene = mi.load_dict(desc)
        integrator = api.make_integrator("identity", inner=1)
        images.append(list(api.passes(scene, integrator, 4, seed=3))[-1].image)
    np.testing.assert_array_equal(images[0], images[1])


def random_points(count: int, seed: int) -> np.ndarray:
    """Points in and around the room: most inside, a fifth outdoors above the roof beyond the
    window wall (behind all three portals: q = 0 there), a tenth in a thin slab around the
    window's plane, where rounding decides the side."""
    rng = np.random.default_rng(seed)
    p = rng.uniform([-1.99, 0.01, -1.99], [1.99, 2.49, 1.99], size=(count, 3))
    out = rng.random(count) < 0.2
    p[out] = rng.uniform([-4.0, 2.6, -2.0], [-2.4, 4.0, 2.0], size=(out.sum(), 3))
    slab = (rng.random(count) < 0.1) & ~out
    p[slab, 0] = -2.0 + rng.uniform(-1e-3, 1e-3, size=slab.sum())
    return p


@pytest.mark.parametrize("mode", ["uniform", "spatial"])
@pytest.mark.parametrize("env", ["constant", "envmap"])
def test_the_density_is_the_one_the_sample_was_drawn_with(mode, env):
    """For next-event samples from random points, `pdf_direction` (what MIS reads where a BSDF
    sample escaped) equals the density the sample was drawn with bit for bit, inside the room and
    behind the portals (where it is the environment's own density times the selection
    probability); and through-portal samples do occur."""
    d = portals_scene()
    d["sky"] = window_room(8, env)["sky"]
    scene = mi.load_dict(d)
    sampler = EmitterSampler(scene, mode)
    n = 1 << 15
    p = random_points(n, 4)
    it = interactions(p)
    u = uniforms(n, 5, 2)
    ds, weight = sampler.sample_direction(it, mi.Point2f(u[0], u[1]), mi.Bool(True), visible=False)
    sky = np.asarray(ds.emitter == mi.EmitterPtr(scene.environment())) & (np.asarray(ds.pdf) > 0)
    assert sky.sum() > n / 4
    got = np.asarray(sampler.pdf_direction(it, ds, mi.Bool(True)))
    np.testing.assert_array_equal(got[sky], np.asarray(ds.pdf)[sky])
    assert np.all(np.isfinite(np.asarray(weight)))
    # behind every portal: q = 0, the density is the environment's own (times 1/2 in `uniform`)
    env_pdf = np.broadcast_to(np.asarray(scene.environment().pdf_direction(it, ds)), n)
    seen = sampler.guide.seen(it.p)
    total = np.asarray(sum((s.omega for s in seen), mi.Float(0.0)))
    outside = sky & (total == 0)
    assert outside.sum() > n / 20
    if mode == "uniform":
        np.testing.assert_allclose(got[outside], (env_pdf * 0.5)[outside], rtol=1e-6)
    # inside: kernel/portal_guide.py's mixture; many samples cross a portal (the portal
    # share's, and the map's through the window)
    portal_pdf = np.asarray(sampler.guide.portal_density(seen, ds.d))
    inside = sky & (total > 0)
    if mode == "uniform":
        want = 0.5 * (SHARE * portal_pdf + (1 - SHARE) * env_pdf)
        np.testing.assert_allclose(got[inside], want[inside], rtol=1e-6)
    assert (sky & (portal_pdf > 0)).sum() > n / 20


@pytest.mark.parametrize("env", ["constant", "envmap"])
@pytest.mark.parametrize("point", [[0.0, 1.0, 0.0], [-1.9, 1.4, 0.1], [1.9, 0.1, 1.9],
                                   [-3.0, 3.0, 0.0]])
def test_the_density_integrates_to_one(env, point):
    """The mixture's density (selection probability taken off) over uniform directions, times
    4 pi, has mean 1 within Z standard errors: at the room's centre, beside the window, in the far
    corner, and outdoors above the roof (behind every portal: the environment's own density)."""
    d = portals_scene()
    del d["lamp"]  # the environment alone: its selection probability is 1
    d["sky"] = window_room(8, env)["sky"]
    scene = mi.load_dict(d)
    sampler = EmitterSampler(scene, "uniform")
    n = 1 << 21
    it = interactions(np.tile(np.array(point, dtype=float), (n, 1)))
    u = uniforms(n, 6, 2)
    si = dr.zeros(mi.SurfaceInteraction3f, n)
    si.wi = -mi.warp.square_to_uniform_sphere(mi.Point2f(u[0], u[1]))
    ds = mi.DirectionSample3f(scene, si, it)
    f = np.asarray(sampler.pdf_direction(it, ds, mi.Bool(True)), dtype=np.float64) * 4 * math.pi
    se = f.std(ddof=1) / math.sqrt(n)
    assert abs(f.mean() - 1.0) < Z * se + 1e-5, (f.mean(), se)


def window_solid_angle(point) -> float:
    """The solid angle of the window seen from a point in the room (float64)."""
    (z0, z1), (y0, y1) = WINDOW_Z, WINDOW_Y
    x, y, z = point
    # in the window's plane x = -2: its edges along z and y, the point at height x + 2
    return solid_angle_reference(z0 - z, z1 - z, y0 - y, y1 - y, x + 2.0)


@pytest.mark.parametrize("point", [[0.0, 1.0, 0.0], [-1.9, 1.4, 0.1], [1.9, 0.1, 1.9]])
def test_the_samples_follow_the_density(point):
    """Under a sky of radiance 1 (red channel) the next-event weights are 1 / density: their
    mean is the sphere's 4 pi, and their mean over the samples that leave through the window is
    the window's solid angle, within Z standard errors. A sampler that drew from other than the
    density it reports (a portal picked in another proportion, a share other than the one the
    density uses) fails this."""
    d = portals_scene()
    del d["lamp"]
    scene = mi.load_dict(d)
    sampler = EmitterSampler(scene, "uniform")
    n = 1 << 20
    it = interactions(np.tile(np.array(point, dtype=float), (n, 1)))
    u = uniforms(n, 8, 2)
    ds, weight = sampler.sample_direction(it, mi.Point2f(u[0], u[1]), mi.Bool(True), visible=False)
    w = np.asarray(mi.Color3f(weight).x, dtype=np.float64)
    dd = np.asarray(ds.d, dtype=np.float64).T
    # the window: where the ray from the point meets the plane x = -2
    t = (-2.0 - point[0]) / np.where(dd[:, 0] < 0, dd[:, 0], -1.0)
    hit = point + t[:, None] * dd
    through = ((dd[:, 0] < 0) & (hit[:, 2] > WINDOW_Z[0]) & (hit[:, 2] < WINDOW_Z[1])
               & (hit[:, 1] > WINDOW_Y[0]) & (hit[:, 1] < WINDOW_Y[1]))
    for values, want in ((w, 4 * math.pi), (w * through, window_solid_angle(point))):
        se = values.std(ddof=1) / math.sqrt(n)
        assert abs(values.mean() - want) < Z * se, (values.mean(), want, se)


# ---- the spherical rectangle

def solid_angle_reference(x0, x1, y0, y1, z):
    """The solid angle of [x0, x1] x [y0, y1] at height z, float64: inclusion-exclusion over the
    rectangles from the foot of the perpendicular, atan(x y / (z r)) each."""
    f = lambda x, y: math.atan(x * y / (abs(z) * math.sqrt(x * x + y * y + z * z)))  # noqa: E731
    return f(x1, y1) - f(x0, y1) - f(x1, y0) + f(x0, y0)


RECTANGLES = [
    (-0.5, 0.7, -0.3, 0.4, -1.0),      # over the point
    (2.0, 3.0, -0.5, 0.5, -0.2),       # off to the side, grazing
    (0.3, 0.8, 0.1, 0.2, -40.0),       # far: 3e-5 sr
    (-0.01, 0.01, 5.0, 5.02, -0.001),  # tiny and edge-on: 3e-9 sr
]


@pytest.mark.parametrize("rect", RECTANGLES)
def test_the_spherical_rectangle_is_sampled_uniformly_in_solid_angle(rect):
    """Its solid angle matches the float64 closed form; every sample lies on the rectangle; the
    share of samples in three sub-rectangles is their share of the solid angle (binomial, Z)."""
    x0, x1, y0, y1, z0 = rect
    F = mi.Float
    omega = float(spherical_rectangle.solid_angle(F(x0), F(x1), F(y0), F(y1), F(z0))[0])
    assert omega == pytest.approx(solid_angle_reference(*rect), rel=1e-5)
    n = 1 << 20
    u = uniforms(n, 7, 2)
    p = spherical_rectangle.sample(F(x0), F(x1), F(y0), F(y1), F(z0), mi.Point2f(u[0], u[1]))
    px, py = np.asarray(p.x), np.asarray(p.y)
    assert np.all((px >= x0) & (px <= x1) & (py >= y0) & (py <= y1))
    assert np.all(np.asarray(p.z) == np.float32(z0))
    for fx, fy in [(0.63, 0.29), (0.2, 0.8), (0.9, 0.9)]:
        xm, ym = x0 + fx * (x1 - x0), y0 + fy * (y1 - y0)
        share = solid_angle_reference(x0, xm, y0, ym, z0) / solid_angle_reference(*rect)
        got = float(((px <= xm) & (py <= ym)).mean())
        assert abs(got - share) < Z * math.sqrt(share * (1 - share) / n), (fx, fy, got, share)


# ---- renders through the window

RES = 32
#: renders per side, and their samples per pixel
SEEDS, SPP = 16, 16
#: |t| bound per 8 x 8 block channel with SEEDS - 1 degrees of freedom (as
#: tests/kernel/test_owen_sobol_sampler.py: P(|t| > 5) = 1.6e-4, 48 block channels)
ZT = 5.0
_cache: dict = {}


def block_means(img: np.ndarray, b: int = 8) -> np.ndarray:
    h, w = img.shape[:2]
    return img.reshape(h // b, b, w // b, b, 3).mean(axis=(1, 3))


def reference(env: str):
    """Mitsuba's `path` on the room without a portal, 2 x 4096 spp: (the mean, the variance of
    that mean per pixel, estimated from the two halves)."""
    if env not in _cache:
        scene = mi.load_dict(window_room(RES, env, portal=False))
        path = mi.load_dict({"type": "path"})
        refs = [np.asarray(mi.render(scene, integrator=path, spp=4096, seed=100 + s), np.float64)
                for s in range(2)]
        _cache[env] = ((refs[0] + refs[1]) / 2, ((refs[0] - refs[1]) / 2) ** 2)
    return _cache[env]


def identity_renders(env: str, portal: bool) -> np.ndarray:
    """SEEDS renders of the room by the identity style at SPP (one path per camera sample)."""
    key = (env, portal)
    if key not in _cache:
        scene = mi.load_dict(window_room(RES, env, portal=portal))
        integrator = api.make_integrator("identity", inner=1)
        _cache[key] = np.stack([
            list(api.passes(scene, integrator, SPP, seed=s))[-1].image[..., :3].astype(np.float64)
            for s in range(SEEDS)])
    return _cache[key]


@pytest.mark.parametrize("env", ["constant", "envmap"])
def test_renders_through_a_portal_converge_to_path_without_one(env):
    """styletrace's identity with the portal against Mitsuba's `path` without it: every 8 x 8
    block within ZT of its standard error (the spread of SEEDS renders plus the reference's)."""
    ref, ref_var = reference(env)
    imgs = identity_renders(env, True)
    blocks = np.stack([block_means(i) for i in imgs])
    var = blocks.var(axis=0, ddof=1) / SEEDS + block_means(ref_var) / 64
    z = (blocks.mean(axis=0) - block_means(ref)) / np.sqrt(var + 1e-12)
    assert np.abs(z).max() < ZT, np.abs(z).max()


@pytest.mark.parametrize("env", ["constant", "envmap"])
def test_a_portal_lowers_the_error_at_equal_samples(env):
    """The mean squared error at SPP (the reference's own variance taken off) with the portal is
    at most RATIO of the error without it. Measured when written: 0.41 (constant), 0.36
    (envmap)."""
    ref, ref_var = reference(env)
    noise = float(ref_var.mean())
    err = {portal: float(np.mean((identity_renders(env, portal) - ref) ** 2)) - noise
           for portal in (True, False)}
    assert err[True] < RATIO * err[False], err


RATIO = 0.5
