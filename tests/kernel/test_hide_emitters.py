"""`hide_emitters` (issue 8, point 4): camera rays do not see emitters, as in Mitsuba's own
`path`; and a scene's own max_depth, carried over to `stylized`, changes the image as it changes
`path`'s."""
import numpy as np
import pytest
from helpers.stats import mean_threshold, mean_z, pixel_t_test

from styletrace.frontends.api import carried_settings, load_scene, make_integrator, passes
from styletrace.frontends.api import scene_dict as scene_dict_of
from styletrace.gate import mi

K = 16                 # independent renders per side
SPP, INNER = 4, 4
RES = 16
ALPHA = 1e-3
Z_MAX = mean_threshold(K)


def scene_dict(integrator=None, near_clip=None):
    T = mi.ScalarTransform4f
    d = {
        "type": "scene",
        # an area light facing the camera, partly in front of a sphere and a floor; a sky around
        # them
        "light": {
            "type": "rectangle",
            "to_world": T().translate([-0.3, 0.2, 0]).scale(0.4),
            "emitter": {"type": "area", "radiance": {"type": "rgb", "value": [4.0, 3.0, 2.0]}},
        },
        "ball": {
            "type": "sphere",
            "radius": 0.4,
            "center": [0.3, -0.1, -0.6],
            "bsdf": {"type": "diffuse"},
        },
        "floor": {
            "type": "rectangle",
            "to_world": T().translate([0, 0, -1]).scale(1.2),
            "bsdf": {"type": "diffuse", "reflectance": {"type": "rgb", "value": [0.7, 0.5, 0.3]}},
        },
        "sky": {"type": "constant", "radiance": {"type": "rgb", "value": [0.5, 0.6, 0.7]}},
        "cam": {
            "type": "perspective",
            "fov": 50,
            "to_world": T().look_at(origin=[0, 0, 3], target=[0, 0, 0], up=[0, 1, 0]),
            "sampler": {"type": "independent"},
            "film": {"type": "hdrfilm", "width": RES, "height": RES, "rfilter": {"type": "box"}},
        },
    }
    if integrator:
        d["integrator"] = integrator
    if near_clip:
        d["cam"]["near_clip"] = near_clip
    return d


def renders(scene, integrator, spp, seed0):
    return np.stack(
        [[p.image for p in passes(scene, integrator, spp, seed=seed0 + k)][-1] for k in range(K)]
    )


def same_means(ours, ref):
    z = mean_z(ours, ref)
    tmax, thr, _ = pixel_t_test(ours, ref, ALPHA)
    return bool(np.all(np.abs(z) < Z_MAX) and tmax < thr), z, tmax, thr


@pytest.fixture(scope="module")
def hidden_path():
    """The truth: Mitsuba's `path` with hide_emitters (a black sky where the camera sees it), its
    camera clipped just past the light (which sits 3 from it; the ball and floor are 3.2 and more
    away), so that camera rays start behind the light as hidden-emitter rays pass through it.
    (Mitsuba 3.9.1's own stepping through hidden area lights shades the ball behind the light
    wrongly: measured 11.6 sd off this truth in the pixels where the two overlap, while ours
    agrees.)"""
    clipped = load_scene(scene_dict(near_clip=3.05))
    return load_scene(scene_dict()), renders(
        clipped, mi.load_dict({"type": "path", "hide_emitters": True}), SPP * INNER, 5000
    )


def test_identity_with_hide_emitters_matches_path(hidden_path):
    scene, ref = hidden_path
    ours = renders(scene, make_integrator("identity", inner=INNER, hide_emitters=True), SPP, 1000)
    ok, z, tmax, thr = same_means(ours, ref)
    assert ok, f"z = {z}, max |t| {tmax:.2f} (threshold {thr:.2f})"
    # the sky is black where the camera sees it, and the light is seen through (not its radiance 4,
    # 3, 2)
    assert np.all(ours[:, 0, 0] == 0.0) and ours[:, :, :, 0].max() < 2.0


def test_the_comparison_rejects_visible_emitters(hidden_path):
    """The same test tells hidden from visible emitters: it is not vacuous."""
    scene, ref = hidden_path
    ours = renders(scene, make_integrator("identity", inner=INNER), SPP, 1000)
    assert not same_means(ours, ref)[0]


def test_hidden_emitters_still_light_the_scene():
    """Only camera rays are affected: the floor behind the light is lit by it and by the sky, and
    a stylized first hit (cel) still sees the light's effect, as with the emitters visible."""
    scene = load_scene(scene_dict())
    shown = [p.image for p in passes(scene, make_integrator("identity", inner=4), 8, seed=3)][-1]
    hidden = [
        p.image
        for p in passes(scene, make_integrator("identity", inner=4, hide_emitters=True), 8, seed=3)
    ][-1]
    floor = (slice(11, 13), slice(6, 10))  # floor pixels below the ball, no light in front
    np.testing.assert_allclose(hidden[floor], shown[floor], rtol=1e-5)


@pytest.mark.parametrize("integrator, expected", [
    ({"type": "path", "max_depth": 6}, {"max_depth": 6, "rr_depth": 5}),
    ({"type": "path"}, {"max_depth": -1, "rr_depth": 5}),
    ({"type": "volpath", "max_depth": 3, "rr_depth": 2, "hide_emitters": True},
     {"max_depth": 3, "rr_depth": 2, "hide_emitters": True}),
    ({"type": "prb", "max_depth": 4}, {"max_depth": 4, "rr_depth": 5}),
    ({"type": "direct", "hide_emitters": True}, {"max_depth": 2, "hide_emitters": True}),
    # the light tracer: Mitsuba prints its unbounded depth as -1 and its binding has no
    # hide_emitters
    ({"type": "ptracer", "max_depth": 3}, {"max_depth": 3, "rr_depth": 5}),
    ({"type": "ptracer"}, {"max_depth": -1, "rr_depth": 5}),
    ({"type": "stylized", "max_depth": 3}, {}),   # its own values are used whole
])
def test_carried_settings_read_mitsubas_integrators(integrator, expected):
    assert carried_settings(load_scene(scene_dict(integrator))) == expected


def test_carried_max_depth_changes_the_image_as_paths_does():
    """A Cornell box with `path` max_depth 2 (direct light only): `stylized` with the carried
    settings matches that path, and not the unbounded one."""
    d = scene_dict_of("cornell-box", RES, RES)
    d["integrator"] = {"type": "path", "max_depth": 2}
    scene = load_scene(d)
    carried = carried_settings(scene)
    ours = renders(scene, make_integrator("identity", inner=INNER, **carried), SPP, 1000)
    ok, z, tmax, thr = same_means(
        ours, renders(scene, mi.load_dict({"type": "path", "max_depth": 2}), SPP * INNER, 5000)
    )
    assert ok, f"z = {z}, max |t| {tmax:.2f} (threshold {thr:.2f})"
    assert not same_means(ours, renders(scene, mi.load_dict({"type": "path"}), SPP * INNER, 9000))[
        0
    ]
