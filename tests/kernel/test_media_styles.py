"""Stylization in scenes with participating media: the identity style at recursive and per-object
vertices equals `volpath`; other styles render (kernel/integrator.py, kernel/volume.py)."""
import numpy as np
from helpers.media import INNER, RES, SPP, T, assert_matches_volpath, fog_ball, lit, sensor

import styletrace  # noqa: F401
from styletrace.frontends.api import make_integrator, passes
from styletrace.gate import mi


def test_first_hit_in_a_chromatic_medium_matches_volpath():
    """With first_hit a camera ray's first collision in a medium is a stylized vertex: the walk's
    throughput there times g's argument, albedo x the in-scattered light, is volpath's weight at
    the collision. A medium whose extinction differs per channel (free flights in one channel per
    path) behind a `null` boundary checks the split per channel."""
    d = lit({"type": "scene", "sensor": sensor(RES),
             "fog": {"type": "homogeneous", "scale": 4.0,
                     "sigma_t": {"type": "rgb", "value": [0.125, 0.375, 1.0]},
                     "albedo": {"type": "rgb", "value": [0.9, 0.6, 0.3]}},
             "cube": {"type": "cube", "to_world": T().scale(0.8), "bsdf": {"type": "null"},
                      "interior": {"type": "ref", "id": "fog"}}})
    assert_matches_volpath(mi.load_dict(d), make_integrator("identity", inner=INNER))


def test_first_n_hits_through_media_matches_volpath():
    """Two stylized levels: the bounce between them flies through the glass sphere's medium."""
    integrator = make_integrator("identity", inner=(2, 2), stylize="first_n_hits", stylize_depth=2)
    assert_matches_volpath(mi.load_dict(fog_ball()), integrator)


def test_first_object_hit_through_media_matches_volpath():
    """The styled floor is stylized where paths reach it, seen through the medium or after
    scattering in it."""
    integrator = make_integrator("identity", inner=INNER, stylize="first_object_hit")
    assert_matches_volpath(mi.load_dict(fog_ball(styled_floor=True)), integrator)


def test_hidden_emitters_in_a_foggy_scene_match_volpath():
    """`hide_emitters`: the environment and an area light seen directly are black (camera rays
    pass the light), what is seen through the glass's fog is not, as in volpath."""
    d = fog_ball()
    d["panel"] = {
        "type": "rectangle",
        "to_world": T().translate([0.9, 0.3, 2.0]) @ T().scale(0.3),
        "emitter": {"type": "area", "radiance": {"type": "rgb", "value": [3.0, 3.0, 3.0]}},
    }
    integrator = make_integrator("identity", inner=INNER, hide_emitters=True)
    assert_matches_volpath(mi.load_dict(d), integrator, {"hide_emitters": True})


def test_a_style_renders_a_scene_with_media():
    """cel on the fog ball: finite, and not the identity image (the style applies at the glass,
    the first scattering of every camera ray that meets the ball)."""
    scene = mi.load_dict(fog_ball())
    cel = list(passes(scene, make_integrator("cel", inner=2), SPP, seed=3))[-1].image
    ident = list(passes(scene, make_integrator("identity", inner=2), SPP, seed=3))[-1].image
    assert np.all(np.isfinite(cel)) and cel.mean() > 0
    assert np.abs(cel - ident).mean() > 0.05 * ident.mean()


def test_lines_in_a_scene_with_media():
    """line_depth 1 draws the camera ray's lines (the glass sphere's outline against the floor);
    the volume walk tests later edges as the surface walk does (line_depth 3 renders:
    tests/kernel/test_media_hooks.py measures those lines). line_mode lifted, whose auxiliary
    paths know no media, refuses a deeper line_depth in one line rather than silently cutting it
    to 1."""
    import pytest

    from styletrace.errors import SceneError
    scene = mi.load_dict(fog_ball())
    red = make_integrator("identity", inner=1, lines=True, line_color="1,0,0", line_depth=1)
    image = list(passes(scene, red, SPP, seed=3))[-1].image
    plain = list(passes(scene, make_integrator("identity", inner=1), SPP, seed=3))[-1].image
    assert np.all(np.isfinite(image))
    # some pixels took the (red) line colour
    assert np.any(np.abs(image - plain).sum(axis=-1) > 0.5)
    deep = make_integrator("identity", inner=1, lines=True, line_color="1,0,0", line_depth=3)
    assert np.all(np.isfinite(list(passes(scene, deep, SPP, seed=3))[-1].image))
    lifted = make_integrator("identity", inner=1, lines=True, line_mode="lifted", line_depth=3)
    with pytest.raises(SceneError, match="bad value 3 for 'line_depth'.*participating media"):
        list(passes(scene, lifted, SPP, seed=3))
