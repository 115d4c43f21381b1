"""Emitter selection: independent of the emitter list's order, probabilities as specified, and
the MIS density at a hit emitter equal to the density with which next-event estimation produced
the direction."""
import itertools
import math

import numpy as np
import pytest

from styletrace.errors import SettingsError
from styletrace.gate import dr, mi
from styletrace.kernel.emitter_sampler import EmitterSampler, selection_order, stable_key

RATIO = 20.0  # radiance of the bright light over the dim one (same area)


def lights_scene(first="dim"):
    """A floor under two equal 0.5 x 0.5 area lights, one RATIO times brighter, plus a point
    light; the insertion order of the lights is `first`-first (Mitsuba mostly lists emitters in
    that order)."""
    T = mi.ScalarTransform4f
    lights = {
        "dim": {
            "type": "rectangle",
            "to_world": T().translate([-1, 2, 0]) @ T().rotate([1, 0, 0], 90) @ T().scale(0.25),
            "emitter": {"type": "area", "radiance": {"type": "rgb", "value": [1.0, 1.0, 1.0]}},
        },
        "bright": {
            "type": "rectangle",
            "to_world": T().translate([1, 2, 0]) @ T().rotate([1, 0, 0], 90) @ T().scale(0.25),
            "emitter": {"type": "area", "radiance": {"type": "rgb", "value": [RATIO] * 3}},
        },
    }
    d = {
        "type": "scene",
        "floor": {
            "type": "rectangle",
            "to_world": T().rotate([1, 0, 0], -90) @ T().scale(3),
            "bsdf": {"type": "diffuse"},
        },
        "bulb": {
            "type": "point",
            "position": [0, 1, 1],
            "intensity": {"type": "rgb", "value": [2.0] * 3},
        },
    }
    for name in ([first] + [n for n in lights if n != first]):
        d[name] = lights[name]
    return d


def scene_with_lights_swapped(scene_dict):
    """The same scene with the two area lights' insertion order reversed."""
    d = dict(scene_dict)
    dim, bright = d.pop("dim"), d.pop("bright")
    return {**d, "bright": bright, "dim": dim}


def test_selection_order_does_not_depend_on_the_list_order():
    scene = mi.load_dict(lights_scene())  # held: an area light's shape dies with its scene
    emitters = list(scene.emitters())
    want = selection_order(emitters)
    for perm in itertools.permutations(emitters):
        assert all(a is b for a, b in zip(selection_order(list(perm)), want))


@pytest.mark.parametrize("mode", ["uniform", "power", "spatial"])
def test_scenes_listed_differently_select_alike(mode):
    """Two loads of one scene agree on the selection order and probabilities (for `spatial`: on
    what it knows of each emitter), whatever Mitsuba listed."""
    a, b = mi.load_dict(lights_scene()), mi.load_dict(scene_with_lights_swapped(lights_scene()))
    sa, sb = EmitterSampler(a, mode), EmitterSampler(b, mode)
    assert sa.keys == sb.keys
    assert sa.probabilities == sb.probabilities
    if mode == "spatial":
        assert sa.bounds == sb.bounds


def test_uniform_and_power_probabilities():
    scene = mi.load_dict(lights_scene())
    assert EmitterSampler(scene, "uniform").probabilities == pytest.approx([1 / 3] * 3)
    power = EmitterSampler(scene, "power")
    p = {
        (
            "area" if e.get_shape() else "point",
            e.get_shape().bbox().min.x if e.get_shape() else 0,
        ): q
        for e, q in zip(sorted(scene.emitters(), key=stable_key), power.probabilities)
    }
    # analytic powers: an area light pi L A, a point light 4 pi I
    phi = {
        ("area", -1.25): math.pi * 1.0 * 0.25,
        ("area", 0.75): math.pi * RATIO * 0.25,
        ("point", 0): 4 * math.pi * 2.0,
    }
    total = sum(phi.values())
    for k, v in phi.items():
        assert p[k] == pytest.approx(v / total, rel=1e-4), (k, p)


def test_unknown_mode_is_refused():
    with pytest.raises(SettingsError,
                       match="'brightest': expected one of auto, uniform, power, spatial"):
        EmitterSampler(mi.load_dict(lights_scene()), "brightest")


def test_spatial_probabilities_need_a_point():
    """`spatial` has no probability per emitter alone: asking for one is an error, not a guess."""
    sampler = EmitterSampler(mi.load_dict(lights_scene()), "spatial")
    assert sampler.probabilities is None
    with pytest.raises(ValueError, match="pdf_direction"):
        sampler.selection_probability(sampler.table, mi.Bool(True))


@pytest.mark.parametrize("mode", ["uniform", "power", "spatial"])
def test_hit_density_matches_the_sampling_density(mode):
    """For directions next-event estimation samples from points on the floor, `pdf_direction`
    (the density MIS uses when a BSDF sample hits the emitter) must equal the density the sample
    was drawn with."""
    scene = mi.load_dict(lights_scene())
    sampler = EmitterSampler(scene, mode)
    n = 4096
    rng = mi.PCG32(n, initseq=dr.arange(mi.UInt64, n))
    si = dr.zeros(mi.SurfaceInteraction3f, n)
    si.p = mi.Point3f(2 * rng.next_float32() - 1, 0.0, 2 * rng.next_float32() - 1)
    si.n = mi.Normal3f(0, 1, 0)
    si.sh_frame = mi.Frame3f(si.n)
    active = mi.Bool(True)
    ds, weight = sampler.sample_direction(
        si, mi.Point2f(rng.next_float32(), rng.next_float32()), active
    )
    area = ~ds.delta & (ds.pdf > 0)
    got = np.asarray(sampler.pdf_direction(mi.Interaction3f(si), ds, area))
    want = np.asarray(ds.pdf)
    m = np.asarray(area)
    assert m.sum() > n / 4
    np.testing.assert_allclose(got[m], want[m], rtol=1e-5)
    if mode == "spatial":  # its picks against its probabilities: tests/kernel/test_spatial_*
        return
    # and every emitter is chosen about as often as its probability says
    ids = np.asarray(dr.reinterpret_array(mi.UInt32, ds.emitter))
    for e, p in zip(sorted(scene.emitters(), key=stable_key), sampler.probabilities):
        k = (ids == dr.reinterpret_array(mi.UInt32, mi.EmitterPtr(e))[0]).sum()
        assert abs(k - n * p) < 5 * math.sqrt(n * p * (1 - p)) + 1, (k, n * p)


def test_auto_is_spatial_with_the_sequence_and_several_lights_else_uniform():
    """`auto`: `spatial` for the built-in scenes' `owen_sobol` sampler with several lights; the
    same scene with independent samples, or one light, keeps `uniform` (today's images)."""
    from styletrace.frontends import api
    assert EmitterSampler(api.load_scene("dragon", 8, 8), "auto").mode == "spatial"
    assert EmitterSampler(api.load_scene("dragon", 8, 8, sampler="independent")).mode == "uniform"
    assert EmitterSampler(api.load_scene("cornell-box", 8, 8)).mode == "uniform"


def test_power_compares_an_area_light_with_a_spot():
    """A spot's sampled weight varies, an area light's is one constant: both count per sample
    (the estimate once divided the constant by its 4096 samples, and the spot won 4000 times over).
    Analytic powers: the area light pi L A; the spot (cutoff 20 deg, beam width 20 deg: constant
    inside) I 2 pi (1 - cos 20 deg)."""
    T = mi.ScalarTransform4f
    scene = mi.load_dict({
        "type": "scene",
        "area": {"type": "rectangle", "to_world": T().translate([0, 2, 0]) @ T().scale(0.25),
                 "emitter": {"type": "area", "radiance": {"type": "rgb", "value": [1.0] * 3}}},
        "spot": {"type": "spot", "to_world": T().look_at(origin=[0, 3, 0], target=[0, 0, 0],
                                                         up=[0, 0, 1]),
                 "intensity": {"type": "rgb", "value": [5.0] * 3},
                 "cutoff_angle": 20.0, "beam_width": 20.0},
    })
    power = EmitterSampler(scene, "power")
    kinds = ["area" if e.get_shape() else "spot"
             for e in sorted(scene.emitters(), key=stable_key)]
    p = dict(zip(kinds, power.probabilities))
    phi_area = math.pi * 1.0 * 0.25
    phi_spot = 5.0 * 2 * math.pi * (1 - math.cos(math.radians(20.0)))
    assert p["area"] == pytest.approx(phi_area / (phi_area + phi_spot), rel=0.02), p
