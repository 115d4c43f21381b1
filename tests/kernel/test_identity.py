"""The identity style reproduces physically based rendering (Mitsuba's own `path` integrator)."""
import numpy as np
import pytest
from helpers.stats import mean_threshold, mean_z, pixel_t_test

import styletrace  # noqa: F401
from styletrace.frontends.api import load_scene, make_integrator, passes
from styletrace.gate import mi

K = 16          # independent renders per side
SPP, INNER = 8, 8
RES = 40
# Family-wise error of the per-pixel test; the mean test uses a Bonferroni bound over 3 channels.
ALPHA = 1e-3
# two-sided 1e-4 over 3 channels, Student's t with 2K - 2 degrees of freedom
Z_MAX = mean_threshold(K)


def renders(scene, integrator, spp, seed0):
    out = []
    for k in range(K):
        *_, last = passes(scene, integrator, spp, seed=seed0 + k)
        out.append(last.image)
    return np.stack(out)


@pytest.mark.parametrize("name", ["cornell-box", "dragon"])
def test_identity_matches_path(name):
    assert_matches_path(load_scene(name, RES, RES), make_integrator("identity", inner=INNER))


def assert_matches_path(scene, integrator):
    """Our renders against Mitsuba's `path` at the same number of light paths: image means and
    per-pixel t."""
    ours = renders(scene, integrator, SPP, 1000)
    ref = renders(scene, mi.load_dict({"type": "path"}), SPP * INNER, 5000)
    z = mean_z(ours, ref)
    assert np.all(np.abs(z) < Z_MAX), f"image means differ: z = {z}"
    tmax, thr, frac = pixel_t_test(ours, ref, ALPHA)
    assert tmax < thr, (
        f"max |t| {tmax:.2f} over Bonferroni threshold {thr:.2f} ({frac:.4%} of pixel channels)"
    )


def two_lights(res):
    """A diffuse sphere on a floor under a large dim area light and a small one 400 times as
    powerful."""
    T = mi.ScalarTransform4f
    return {
        "type": "scene",
        "sensor": {
            "type": "perspective",
            "fov": 40,
            "to_world": T().look_at(origin=[0, 2.5, 4.5], target=[0, 0.4, 0], up=[0, 1, 0]),
            "sampler": {"type": "independent"},
            "film": {"type": "hdrfilm", "width": res, "height": res, "rfilter": {"type": "box"}},
        },
        "floor": {
            "type": "rectangle",
            "to_world": T().rotate([1, 0, 0], -90) @ T().scale(3),
            "bsdf": {"type": "diffuse", "reflectance": {"type": "rgb", "value": [0.6, 0.6, 0.6]}},
        },
        "ball": {
            "type": "sphere",
            "center": [0, 0.5, 0],
            "radius": 0.5,
            "bsdf": {"type": "diffuse", "reflectance": {"type": "rgb", "value": [0.7, 0.4, 0.2]}},
        },
        "dim": {
            "type": "rectangle",
            "to_world": T().translate([-1.0, 2.5, 0]) @ T().rotate([1, 0, 0], 90) @ T().scale(1.0),
            "emitter": {"type": "area", "radiance": {"type": "rgb", "value": [0.5, 0.5, 0.5]}},
        },
        "bright": {
            "type": "rectangle",
            "to_world": T().translate([1.2, 2.0, 0.5]) @ T().rotate([1, 0, 0], 90) @ T().scale(0.1),
            "emitter": {"type": "area", "radiance": {"type": "rgb", "value": [2000.0] * 3}},
        },
    }


@pytest.mark.parametrize("mode", ["uniform", "power", "spatial"])
def test_identity_matches_path_with_lights_of_very_different_power(mode):
    """Our emitter selection (every mode) against Mitsuba's, with the same tests as above."""
    integrator = make_integrator("identity", inner=INNER, emitter_sampling=mode)
    assert integrator.settings.emitter_sampling == mode
    assert_matches_path(mi.load_dict(two_lights(RES)), integrator)


def test_identity_test_detects_a_darker_scene():
    """The same tests reject a reference whose albedos are 3% darker: they are not vacuous."""
    scene = load_scene("cornell-box", RES, RES)
    d = styletrace.frontends.api.scene_dict("cornell-box", RES, RES)
    for key in ("white", "red", "green"):
        d[key]["reflectance"]["value"] = [0.97 * v for v in d[key]["reflectance"]["value"]]
    darker = mi.load_dict(d)
    ours = renders(scene, make_integrator("identity", inner=INNER), SPP, 1000)
    ref = renders(darker, mi.load_dict({"type": "path"}), SPP * INNER, 5000)
    assert np.any(np.abs(mean_z(ours, ref)) > Z_MAX)
