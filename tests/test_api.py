"""The Python API: scene loading, integrator construction, rendering in passes."""
import mitsuba as mi
import numpy as np
import pytest

import styletrace
from styletrace import api
from styletrace.errors import SettingsError, StyleError


def test_render_returns_linear_float32_hwc():
    img = styletrace.render("cornell-box", style="cel", spp=2, inner=2, width=20, height=12, levels=(0.3, 0.9))
    assert img.dtype == np.float32 and img.shape == (12, 20, 3) and np.isfinite(img).all()


def test_passes_average_is_weighted_by_samples():
    """Unequal passes (4 + 2 spp) combine as (4 a + 2 b) / 6, each pass with its own derived seed."""
    scene = api.load_scene("cornell-box", 8, 8)
    integ = api.make_integrator("identity", inner=1)
    progress = list(api.passes(scene, integ, 6, seed=5, lanes_per_pass=4 * 64))
    assert [p.spp_done for p in progress] == [4, 6]
    a = np.array(mi.render(scene, integrator=integ, spp=4, seed=api.pass_seed(5, 0)), dtype=np.float64)
    b = np.array(mi.render(scene, integrator=integ, spp=2, seed=api.pass_seed(5, 1)), dtype=np.float64)
    np.testing.assert_allclose(progress[-1].image, ((4 * a + 2 * b) / 6).astype(np.float32), rtol=1e-6)
    assert api.pass_count(scene, 6, 4 * 64) == 2


def test_pass_seeds_differ():
    seeds = {api.pass_seed(s, i) for s in range(4) for i in range(64)}
    assert len(seeds) == 4 * 64


@pytest.mark.parametrize("scene,kwargs,message", [
    ("no-such", {}, "unknown scene 'no-such'"),
    ("missing.xml", {}, "scene file 'missing.xml' does not exist"),
    ({"type": "scene", "s": {"type": "spheer"}}, {}, "cannot load scene dict"),
    ({"type": "scene"}, {"width": 8}, "width/height apply to built-in scenes and XML files"),
])
def test_scene_errors(scene, kwargs, message):
    with pytest.raises(api.SceneError, match=message):
        api.load_scene(scene, **kwargs)


def test_loaded_scene_cannot_be_resized():
    scene = api.load_scene("furnace", 8, 8)
    assert api.load_scene(scene, 8, 8) is scene
    with pytest.raises(api.SceneError, match="cannot change an already loaded"):
        api.load_scene(scene, 16, 8)


def test_make_integrator_validates_before_mitsuba():
    with pytest.raises(StyleError, match="bad value 'x' for parameter 'gamma'"):
        api.make_integrator("gamma", gamma="x")
    with pytest.raises(SettingsError, match="expected 1 or 2 counts"):
        api.make_integrator("cel", inner=(2, 3, 4), stylize="first_n_hits", stylize_depth=2)
    with pytest.raises(SettingsError, match="stylize_depth"):
        api.make_integrator("cel", stylize_depth=2)
    with pytest.raises(SettingsError, match="the integrator's own style must be identity"):
        api.make_integrator("cel", stylize="first_object_hit")


def test_gradient_given_as_stops():
    integ = api.make_integrator("color_map", gradient=[(0, (0, 0, 0)), (1, (1, 0.5, 0))])
    assert "0:0,0,0;1:1,0.5,0" in integ.settings.style.describe()
