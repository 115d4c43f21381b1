"""`stylized` as Mitsuba builds it (scene/standalone.py): `mi.render` resolves the style's auto
values on the scene once, caches them per scene, and renders what the pipeline renders."""
import numpy as np

import styletrace
from styletrace.gate import mi
from styletrace.pipeline.passes import pass_seed
from styletrace.scene import standalone
from styletrace.scene.builtin import BUILTIN


def scene_with(integrator: dict) -> mi.Scene:
    d = BUILTIN["cornell-box"](width=12, height=12)
    d["integrator"] = integrator
    return mi.load_dict(d)


def test_auto_values_resolve_once_per_scene(monkeypatch):
    calls = []
    real = standalone.resolve_defaults
    monkeypatch.setattr(
        standalone, "resolve_defaults", lambda scene, integ: calls.append(1) or real(scene, integ)
    )
    scene = scene_with({"type": "stylized", "style": "cel", "inner_samples": 2})
    first = np.array(mi.render(scene, spp=2, seed=3))
    second = np.array(mi.render(scene, spp=2, seed=3))
    assert len(calls) == 1 and np.array_equal(first, second)
    other = scene_with({"type": "stylized", "style": "cel", "inner_samples": 2})
    mi.render(other, integrator=scene.integrator(), spp=1)  # another scene: resolved again
    assert len(calls) == 2


def test_mi_render_equals_the_pipelines_one_pass():
    """Cel (auto thresholds) and reuse=pixels with its refinement round: mi.render on the scene's
    own integrator is `styletrace.render` of the same scene for the pass seed of the pipeline's
    only pass."""
    for values in ({"style": "cel", "inner_samples": 2},
                   {"style": "cel", "inner_samples": "2:8", "reuse": "pixels"}):
        scene = scene_with({"type": "stylized", **values})
        mine = np.array(mi.render(scene, spp=2, seed=pass_seed(4, 0)))[..., :3]
        assert np.array_equal(mine, styletrace.render(scene, spp=2, seed=4)), values


def test_integrators_built_from_values_keep_mitsubas_render():
    """Only Mitsuba-built integrators get the resolving `render` (on the instance): the
    pipeline's own do not."""
    built = mi.load_dict({"type": "stylized", "style": "cel"})
    assert "render" in vars(built)
    assert "render" not in vars(styletrace.frontends.api.make_integrator("cel"))
