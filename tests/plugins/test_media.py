"""Participating media: with the identity style `stylized` equals Mitsuba's `volpath` (plugins/volume.py).

Every comparison renders K independent images per side at the same number of light paths and tests the
difference of the image means against its standard error (`mean_z`) and each pixel block (`pixel_t_test`).
"""
import mitsuba as mi
import numpy as np
import pytest

import styletrace  # noqa: F401
from styletrace.api import make_integrator, passes
from helpers.stats import mean_threshold, mean_z, pixel_t_test

K, RES = 10, 24
SPP, INNER = 4, 4
Z_MAX = mean_threshold(K)
T = mi.ScalarTransform4f


def renders(scene, integrator, spp, seed0):
    return np.stack([list(passes(scene, integrator, spp, seed=seed0 + k))[-1].image for k in range(K)])


def assert_matches_volpath(scene, integrator, volpath=None, block=4):
    ours = renders(scene, integrator, SPP, 1000)
    ref = renders(scene, mi.load_dict({"type": "volpath", **(volpath or {})}), SPP * INNER, 5000)
    assert np.all(np.isfinite(ours))
    z = mean_z(ours, ref)
    assert np.all(np.abs(z) < Z_MAX), f"image means differ from volpath: z = {z}"
    tmax, thr, frac = pixel_t_test(ours, ref, 1e-3, block=block)
    assert tmax < thr, f"max |t| {tmax:.2f} over threshold {thr:.2f} ({frac:.3%} of blocks)"
    return z


def sensor(res, origin=(0, 0.6, 4.0), **extra):
    return {"type": "perspective", "fov": 40, "sampler": {"type": "independent"},
            "to_world": T().look_at(origin=list(origin), target=[0, 0.1, 0], up=[0, 1, 0]),
            "film": {"type": "hdrfilm", "width": res, "height": res, "rfilter": {"type": "box"}}, **extra}


def diffuse(rgb, styled=False):
    b = {"type": "diffuse", "reflectance": {"type": "rgb", "value": rgb}}
    return {"type": "styled", "style": "identity", "inner_samples": 2, "bsdf": b} if styled else b


def lit(d, env=True):
    """Floor, an area light above, a point light and (optionally) a constant environment."""
    d["floor"] = {"type": "rectangle", "to_world": T().translate([0, -1, 0]) @ T().rotate([1, 0, 0], -90) @ T().scale(4),
                  "bsdf": d.pop("floor_bsdf", diffuse([0.6, 0.6, 0.6]))}
    d["light"] = {"type": "rectangle", "to_world": T().translate([0.5, 2.5, 0.5]) @ T().rotate([1, 0, 0], 90) @ T().scale(0.8),
                  "emitter": {"type": "area", "radiance": {"type": "rgb", "value": [5.0, 4.5, 4.0]}}}
    d["point"] = {"type": "point", "position": [-1.5, 1.5, 1.5], "intensity": {"type": "rgb", "value": [3.0, 3.0, 3.0]}}
    if env:
        d["env"] = {"type": "constant", "radiance": {"type": "rgb", "value": [0.3, 0.35, 0.4]}}
    return d


def fog_ball(res=RES, styled_floor=False, ior=1.33):
    """The issue's scene: a chromatic homogeneous medium inside a glass sphere."""
    return lit({"type": "scene", "sensor": sensor(res),
                "fog": {"type": "homogeneous", "sigma_t": {"type": "rgb", "value": [0.5, 0.7, 1.0]}, "scale": 2.0,
                        "albedo": {"type": "rgb", "value": [0.9, 0.7, 0.5]}},
                "ball": {"type": "sphere", "radius": 0.9, "bsdf": {"type": "dielectric", "int_ior": ior},
                         "interior": {"type": "ref", "id": "fog"}},
                "floor_bsdf": diffuse([0.6, 0.6, 0.6], styled_floor)})


def smoke_cube(res=RES):
    """A heterogeneous medium (a 6^3 grid of densities) bounded by a `null` cube, anisotropic phase."""
    x = np.linspace(-1, 1, 6)
    zz, yy, xx = np.meshgrid(x, x, x, indexing="ij")
    density = np.clip(1.2 - (xx ** 2 + yy ** 2 + zz ** 2), 0.0, None) * 3.0
    grid = mi.VolumeGrid(density[..., None].astype(np.float32))
    box = T().scale(0.8)
    return lit({"type": "scene", "sensor": sensor(res),
                "smoke": {"type": "heterogeneous", "albedo": 0.8, "phase": {"type": "hg", "g": 0.4},
                          "sigma_t": {"type": "gridvolume", "grid": grid, "to_world": box @ T().translate([-1, -1, -1])
                                      @ T().scale(2)}},
                "cube": {"type": "cube", "to_world": box, "bsdf": {"type": "null"},
                         "interior": {"type": "ref", "id": "smoke"}}})


def foggy_room(res=RES):
    """The camera stands in a thin homogeneous fog that fills the whole scene (the sensor's medium)."""
    d = lit({"type": "scene",
             "fog": {"type": "homogeneous", "sigma_t": 0.25, "albedo": {"type": "rgb", "value": [0.8, 0.8, 0.9]}},
             "ball": {"type": "sphere", "radius": 0.7, "bsdf": diffuse([0.7, 0.4, 0.2])}}, env=False)
    d["sensor"] = sensor(res, medium={"type": "ref", "id": "fog"})
    return d


SCENES = {"fog_ball": fog_ball, "smoke_cube": smoke_cube, "foggy_room": foggy_room}


@pytest.mark.parametrize("name", list(SCENES))
def test_identity_matches_volpath(name):
    assert_matches_volpath(mi.load_dict(SCENES[name]()), make_integrator("identity", inner=INNER))


def test_the_comparison_detects_media_ignored():
    """Mitsuba's `path` (which ignores media) against volpath, by the same test: far apart (the issue's z = 58)."""
    scene = mi.load_dict(fog_ball())
    ours = renders(scene, mi.load_dict({"type": "path"}), SPP * INNER, 1000)
    ref = renders(scene, mi.load_dict({"type": "volpath"}), SPP * INNER, 5000)
    assert np.any(np.abs(mean_z(ours, ref)) > Z_MAX)


def test_first_n_hits_through_media_matches_volpath():
    """Two stylized levels: the bounce between them flies through the glass sphere's medium."""
    integrator = make_integrator("identity", inner=(2, 2), stylize="first_n_hits", stylize_depth=2)
    assert_matches_volpath(mi.load_dict(fog_ball()), integrator)


def test_first_object_hit_through_media_matches_volpath():
    """The styled floor is stylized where paths reach it, seen through the medium or after scattering in it."""
    integrator = make_integrator("identity", inner=INNER, stylize="first_object_hit")
    assert_matches_volpath(mi.load_dict(fog_ball(styled_floor=True)), integrator)


def test_hidden_emitters_in_a_foggy_scene_match_volpath():
    """`hide_emitters`: the environment seen directly (through the glass's fog too) is black, as in volpath."""
    integrator = make_integrator("identity", inner=INNER, hide_emitters=True)
    assert_matches_volpath(mi.load_dict(fog_ball()), integrator, {"hide_emitters": True})


def test_a_style_renders_a_scene_with_media():
    """cel on the fog ball: finite, and not the identity image (the style applies at surface vertices)."""
    scene = mi.load_dict(fog_ball())
    cel = list(passes(scene, make_integrator("cel", inner=INNER), SPP, seed=3))[-1].image
    ident = list(passes(scene, make_integrator("identity", inner=INNER), SPP, seed=3))[-1].image
    assert np.all(np.isfinite(cel)) and cel.mean() > 0
    assert np.abs(cel - ident).mean() > 0.05 * ident.mean()


def test_the_media_switch_is_off_without_media():
    """Scenes without media trace the plain path kernel (path.walk), those with media the volumetric one."""
    plain = fog_ball()
    del plain["ball"]["interior"]
    for d, media in ((plain, False), (fog_ball(), True), (foggy_room(), True)):
        integrator = make_integrator("identity")
        integrator._targets(mi.load_dict(d))
        assert integrator.media is media
