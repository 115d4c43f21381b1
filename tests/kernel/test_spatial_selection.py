"""Spatial emitter selection (`emitter_sampling spatial`): the density MIS reads is exactly the one
the sample was drawn with, the picks follow it, no emitter that can light a point is left out,
and next-event estimation with it converges to the analytic irradiance, as with uniform
selection."""
import math

import numpy as np
import pytest
from helpers.media import INNER, assert_matches_volpath, foggy_room

from styletrace.frontends.api import make_integrator
from styletrace.gate import dr, mi
from styletrace.kernel import spatial_selection
from styletrace.kernel.emitter_sampler import EmitterSampler, emitter_id, selection_order

T = mi.ScalarTransform4f
#: z beyond which a mean is rejected: a two-sided 5.7e-7 per test, at most a few hundred tests
Z = 5.0


def rgb(v: float) -> dict:
    return {"type": "rgb", "value": [v] * 3}


def area(shape: dict, radiance: float) -> dict:
    return {**shape, "emitter": {"type": "area", "radiance": rgb(radiance)}}


def all_kinds() -> dict:
    """Nine emitters of every kind: rectangles facing down and sideways, a disk, a small
    sphere, a point light, a spot, a sky and a sun (and a floor, for the scene's bounds)."""
    return {
        "type": "scene",
        "floor": {"type": "rectangle", "to_world": T().rotate([1, 0, 0], -90) @ T().scale(3)},
        "down": area({"type": "rectangle", "to_world": T().translate([-1, 2.5, 0])
                      @ T().rotate([1, 0, 0], 90) @ T().scale(0.5)}, 5.0),
        "side": area({"type": "rectangle", "to_world": T().translate([2, 1, 0])
                      @ T().rotate([0, 1, 0], -90) @ T().scale(0.3)}, 10.0),
        "disk": area({"type": "disk", "to_world": T().translate([0, 2, -2]) @ T().scale(0.4)},
                     3.0),
        "ball": area({"type": "sphere", "center": [-2, 1, 2], "radius": 0.2}, 4.0),
        "bulb": {"type": "point", "position": [1, 1.5, 1], "intensity": rgb(3.0)},
        "spot": {"type": "spot", "cutoff_angle": 30.0, "intensity": rgb(20.0),
                 "to_world": T().look_at(origin=[0, 3, 0], target=[0, 0, 0], up=[0, 0, 1])},
        "sky": {"type": "constant", "radiance": rgb(0.3)},
        "sun": {"type": "directional", "direction": [1, -1, 0], "irradiance": rgb(2.0)},
    }


def interactions(p: np.ndarray, n: np.ndarray) -> mi.Interaction3f:
    it = dr.zeros(mi.Interaction3f, len(p))
    it.p = mi.Point3f(*(mi.Float(p[:, i].astype(np.float32)) for i in range(3)))
    it.n = mi.Normal3f(*(mi.Float(n[:, i].astype(np.float32)) for i in range(3)))
    return it


def random_points(count: int, seed: int):
    """Points in a box around the lights, three in four with a random unit normal, the rest
    without (medium collisions); a quarter of them in a thin slab around the plane of the `down`
    light, where rounding decides which side a point is on."""
    rng = np.random.default_rng(seed)
    p = rng.uniform([-3, -0.5, -3], [3, 3.5, 3], size=(count, 3))
    slab = rng.random(count) < 0.25
    p[slab, 1] = 2.5 + rng.uniform(-1e-2, 1e-2, size=slab.sum())
    p[slab, 0] = rng.uniform(-2.0, 0.0, size=slab.sum())
    p[slab, 2] = rng.uniform(-1.0, 1.0, size=slab.sum())
    n = rng.normal(size=(count, 3))
    n /= np.linalg.norm(n, axis=1, keepdims=True)
    n[rng.random(count) < 0.25] = 0.0
    return p, n


def uniforms(count: int, seed: int, dims: int) -> list:
    rng = mi.PCG32(count, initseq=dr.arange(mi.UInt64, count) + seed)
    return [rng.next_float32() for _ in range(dims)]


@pytest.fixture(params=["unrolled", "loop"])
def walk(request, monkeypatch):
    """Both ways of walking over the emitters: unrolled, and as a Dr.Jit loop (the one scenes with
    more than UNROLL emitters get)."""
    if request.param == "loop":
        monkeypatch.setattr(spatial_selection, "UNROLL", 0)
    return request.param


def test_the_density_is_the_one_the_sample_was_drawn_with(walk):
    scene = mi.load_dict(all_kinds())
    sampler = EmitterSampler(scene, "spatial")
    assert sampler.spatial.unrolled == (walk == "unrolled")
    n = 1 << 14
    it = interactions(*random_points(n, 1))
    u = uniforms(n, 2, 2)
    active = mi.Bool(True)
    # the selection probability: bit for bit
    index, _, pmf = sampler.spatial.sample(it, u[0], active)
    again = sampler.spatial.pmf(it, index, active)
    assert np.array_equal(np.asarray(pmf), np.asarray(again))
    assert np.all(np.asarray(pmf) > 0)  # every point here has lights that reach it
    # the solid-angle density MIS reads at the emitter the direction reached
    ds, weight = sampler.sample_direction(it, mi.Point2f(u[0], u[1]), active, visible=False)
    # (Mitsuba's area lights keep the density of a sample that reached their back, weight 0)
    area = ~ds.delta & (ds.pdf > 0) & (dr.max(weight) > 0)
    got = np.asarray(sampler.pdf_direction(it, ds, area))
    want, m = np.asarray(ds.pdf), np.asarray(area)
    assert m.sum() > n / 4
    # the emitter's own density times the very probability the pick was made with ...
    own = np.asarray(ds.emitter.pdf_direction(it, ds, area))
    np.testing.assert_array_equal(got[m], (own * np.asarray(pmf))[m])
    # ... which is the density of the sample (up to Mitsuba's own rounding, worst at grazing
    # angles)
    np.testing.assert_allclose(got[m], want[m], rtol=1e-4)


@pytest.mark.parametrize("point, normal", [
    ([0.5, 0.0, 0.5], [0, 1, 0]),     # on the floor
    ([-1.2, 2.7, 0.1], [0, 0, 0]),    # in a medium, above (behind) the `down` light
    ([1.5, 1.0, -0.3], [1, 0, 0]),    # in front of the `side` light, facing away from it
])
def test_picks_follow_the_probabilities(point, normal, walk):
    """At one point, how often each emitter is picked matches the probability `pmf` gives it
    (5 standard deviations), and the probabilities sum to 1."""
    scene = mi.load_dict(all_kinds())
    sampler = EmitterSampler(scene, "spatial")
    n = 1 << 16
    it = interactions(np.tile(point, (n, 1)), np.tile(normal, (n, 1)))
    index, reused, _ = sampler.spatial.sample(it, uniforms(n, 3, 1)[0], mi.Bool(True))
    index = np.asarray(index)
    probs = []
    for k in range(sampler.count):
        p = float(np.asarray(sampler.spatial.pmf(it, mi.UInt32(k), mi.Bool(True)))[0])
        probs.append(p)
        count = int((index == k).sum())
        assert abs(count - n * p) < Z * math.sqrt(n * p * (1 - p)) + 1, (k, count, n * p)
    assert sum(probs) == pytest.approx(1.0, rel=1e-5)
    # the reused sample is uniform again: its mean and its share below 1/4
    r = np.asarray(reused)
    assert abs(r.mean() - 0.5) < Z * math.sqrt(1 / 12 / n)
    assert abs((r < 0.25).mean() - 0.25) < Z * math.sqrt(0.25 * 0.75 / n)


def test_no_emitter_that_can_light_a_point_is_left_out(walk):
    """Wherever an emitter's own sampling finds light reaching a point (64 tries per point), its
    probability there is positive; and the cones do leave some out (points behind the one-sided
    lights, outside the spot's cone), with no light found there either."""
    scene = mi.load_dict(all_kinds())
    sampler = EmitterSampler(scene, "spatial")
    points, tries = 1 << 12, 64
    p, nrm = random_points(points, 4)
    it = interactions(p, nrm)
    many = interactions(np.repeat(p, tries, axis=0), np.repeat(nrm, tries, axis=0))
    u = uniforms(points * tries, 5, 2)
    excluded = {}
    for k, (key, emitter) in enumerate(zip(sampler.keys, selection_order(scene.emitters()))):
        ds, weight = emitter.sample_direction(many, mi.Point2f(u[0], u[1]), mi.Bool(True))
        lit = np.broadcast_to(np.asarray((dr.max(weight) > 0) & (ds.pdf > 0)), points * tries)
        lit = lit.reshape(points, tries).any(axis=1)
        pmf = np.asarray(sampler.spatial.pmf(it, mi.UInt32(k), mi.Bool(True)))
        name = key[0].split("[")[0]
        assert np.all(pmf[lit] > 0), (name, int((pmf[lit] == 0).sum()))
        excluded[name] = excluded.get(name, 0) + int((pmf == 0).sum())
        assert not np.any(lit[pmf == 0])
    assert excluded["SpotLight"] > points / 4
    assert excluded["AreaLight"] > points / 8  # the lights' back sides (summed by name)


def test_a_point_no_emitter_can_light_gets_no_sample():
    """Behind the only (one-sided) light: no pick, weight and density 0, nothing undefined."""
    d = all_kinds()
    scene = mi.load_dict({"type": "scene", "floor": d["floor"], "down": d["down"]})
    sampler = EmitterSampler(scene, "spatial")
    n = 256
    it = interactions(np.tile([-1.0, 4.0, 0.0], (n, 1)), np.tile([0, 1, 0], (n, 1)))
    u = uniforms(n, 6, 2)
    ds, weight = sampler.sample_direction(it, mi.Point2f(u[0], u[1]), mi.Bool(True),
                                          visible=False)
    assert np.all(np.asarray(ds.pdf) == 0) and np.all(np.asarray(weight) == 0)
    assert np.all(np.asarray(sampler.spatial.pmf(it, mi.UInt32(0), mi.Bool(True))) == 0)


def test_loop_and_unrolled_walks_agree(monkeypatch):
    scene = mi.load_dict(all_kinds())
    it = interactions(*random_points(1 << 12, 7))
    out = []
    for unroll in (spatial_selection.UNROLL, 0):
        monkeypatch.setattr(spatial_selection, "UNROLL", unroll)
        sampler = EmitterSampler(scene, "spatial")
        out.append(np.stack([np.asarray(sampler.spatial.pmf(it, mi.UInt32(k), mi.Bool(True)))
                             for k in range(sampler.count)]))
    np.testing.assert_allclose(out[0], out[1], rtol=1e-5, atol=1e-12)


# ---- next-event estimation against the analytic irradiance

LAMP = 5.0        # radiance of the two rectangles
BULB = 3.0        # intensity of the point light
SKY = 0.3         # radiance of the constant environment
SUN = 2.0         # irradiance of the sun, along SUN_DIR
SUN_DIR = np.array([1.0, -2.0, 0.0]) / math.sqrt(5.0)


def irradiance_scene() -> dict:
    """Lights all above the floor y = 0, facing it: a large and a small rectangle (one tilted),
    a point light, a sky and a sun."""
    return {
        "type": "scene",
        "big": area({"type": "rectangle", "to_world": T().translate([-0.5, 2.0, 0])
                     @ T().rotate([1, 0, 0], 90) @ T().scale(0.6)}, LAMP),
        "small": area({"type": "rectangle", "to_world": T().translate([1.5, 1.2, 0.5])
                       @ T().rotate([0, 0, 1], -30) @ T().rotate([1, 0, 0], 90)
                       @ T().scale(0.1)}, LAMP * 30),
        "bulb": {"type": "point", "position": [0.8, 1.0, -1.0], "intensity": rgb(BULB)},
        "sky": {"type": "constant", "radiance": rgb(SKY)},
        "sun": {"type": "directional", "direction": SUN_DIR.tolist(), "irradiance": rgb(SUN)},
    }


def polygon_irradiance(x: np.ndarray, n: np.ndarray, corners: np.ndarray, radiance: float):
    """Irradiance at x (normal n) from a Lambertian polygon wholly above x's tangent plane and
    facing x (Lambert's formula: L/2 times the sum over edges of the angle they subtend times the
    cosine of their plane's normal with n)."""
    v = corners - x
    v /= np.linalg.norm(v, axis=1, keepdims=True)
    total = 0.0
    for i in range(len(v)):
        a, b = v[i], v[(i + 1) % len(v)]
        c = np.cross(a, b)
        total += math.acos(np.clip(a @ b, -1, 1)) * (c @ n) / np.linalg.norm(c)
    return radiance / 2 * abs(total)


def rectangle_corners(to_world: mi.ScalarTransform4f) -> np.ndarray:
    m = np.asarray(to_world.matrix, dtype=np.float64).reshape(4, 4)
    local = np.array([[-1, -1, 0, 1], [1, -1, 0, 1], [1, 1, 0, 1], [-1, 1, 0, 1]], dtype=float)
    return (local @ m.T)[:, :3]


def analytic_irradiance(x: np.ndarray, n: np.ndarray) -> float:
    d = irradiance_scene()
    e = polygon_irradiance(x, n, rectangle_corners(d["big"]["to_world"]), LAMP)
    e += polygon_irradiance(x, n, rectangle_corners(d["small"]["to_world"]), LAMP * 30)
    to_bulb = np.array([0.8, 1.0, -1.0]) - x
    e += BULB * max(to_bulb @ n, 0) / np.linalg.norm(to_bulb) ** 3
    return e + math.pi * SKY + SUN * max(-SUN_DIR @ n, 0.0)


def nee_irradiance(sampler: EmitterSampler, x: np.ndarray, n: np.ndarray, samples: int):
    """Per point: (the mean and the standard error of L cos / pdf over `samples` next-event
    samples, the same with the probability of each pick taken as 1/N)."""
    count = len(x)
    it = interactions(np.repeat(x, samples, axis=0), np.repeat(n, samples, axis=0))
    u = uniforms(count * samples, 8, 2)
    ds, weight = sampler.sample_direction(it, mi.Point2f(u[0], u[1]), mi.Bool(True),
                                          visible=False)
    cos = dr.maximum(dr.dot(ds.d, mi.Vector3f(it.n)), 0.0)
    f = np.asarray(mi.Color3f(weight).x * cos, dtype=np.float64).reshape(count, samples)
    out = [(f.mean(axis=1), f.std(axis=1, ddof=1) / math.sqrt(samples))]
    if sampler.spatial is not None:
        known = ds.emitter != None  # noqa: E711  (a Dr.Jit pointer comparison)
        index = dr.gather(mi.UInt32, sampler.index_by_id, emitter_id(ds.emitter), known)
        pmf = np.asarray(sampler.spatial.pmf(it, index, known), dtype=np.float64)
        wrong = f * (pmf * sampler.count).reshape(count, samples)
        out.append((wrong.mean(axis=1), wrong.std(axis=1, ddof=1) / math.sqrt(samples)))
    return out


@pytest.mark.parametrize("mode", ["uniform", "power", "spatial"])
def test_next_event_estimation_converges_to_the_analytic_irradiance(mode):
    """The mean of weight x cos over many samples at 16 floor points is the analytic irradiance
    within Z standard errors, for every mode; for spatial, the same test rejects an estimate that
    takes its picks as uniform (it would pass a wrong density unnoticed otherwise)."""
    scene = mi.load_dict(irradiance_scene())
    sampler = EmitterSampler(scene, mode)
    g = np.linspace(-1.8, 1.8, 4)
    x = np.array([[a, 0.0, b] for a in g for b in g])
    n = np.tile([0.0, 1.0, 0.0], (len(x), 1))
    want = np.array([analytic_irradiance(p, q) for p, q in zip(x, n)])
    results = nee_irradiance(sampler, x, n, 1 << 14)
    mean, se = results[0]
    z = (mean - want) / np.maximum(se, 1e-6 * want)
    assert np.all(np.abs(z) < Z), (z, mean, want)
    if mode == "spatial":
        mean, se = results[1]
        assert np.max(np.abs((mean - want) / se)) > Z


def test_a_foggy_room_matches_volpath():
    """The wiring in media (kernel/volume.py: light sampled and MIS densities asked from medium
    collisions, which have no normal): the render runs, stays finite and matches Mitsuba's
    `volpath`. (Too noisy to see a wrong MIS density: the densities at points without a normal are
    checked in test_the_density_is_the_one_the_sample_was_drawn_with.)"""
    assert_matches_volpath(mi.load_dict(foggy_room()),
                           make_integrator("identity", inner=INNER, emitter_sampling="spatial"))
