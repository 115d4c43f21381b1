"""What spatial emitter selection knows of each emitter: the cones it excludes points with are the
emitters' true normals (flipped or not) or beams, and the strengths are the analytic ones."""
import math

import numpy as np
import pytest

from styletrace.gate import mi
from styletrace.kernel.emitter_bounds import (
    ANGLE_MARGIN,
    DIRECTIONAL,
    ENVIRONMENT,
    FINITE,
    emitted_power,
    emitter_bounds,
)

T = mi.ScalarTransform4f
#: the scenes of `only_emitter`: an area light's shape dies with its scene
SCENES = []


def only_emitter(d: dict) -> mi.Emitter:
    """The one emitter of a scene holding `d` (the scene is kept in SCENES)."""
    SCENES.append(mi.load_dict({"type": "scene", "it": d}))
    return SCENES[-1].emitters()[0]


def area(shape: dict, radiance: float = 2.0) -> dict:
    return {**shape, "emitter": {"type": "area", "radiance": {"type": "rgb",
                                                             "value": [radiance] * 3}}}


def quad_ply(path) -> str:
    """A 2 x 2 quad in the plane y = 0.5, its faces wound to face +Y, as a PLY file."""
    mesh = mi.Mesh("quad", 4, 2)
    params = mi.traverse(mesh)
    v = np.array([[-1, 0.5, -1], [1, 0.5, -1], [1, 0.5, 1], [-1, 0.5, 1]], dtype=np.float32)
    params["vertex_positions"] = mi.Float(v.ravel())
    params["faces"] = mi.UInt32(np.array([[0, 2, 1], [0, 3, 2]], dtype=np.uint32).ravel())
    params.update()
    name = str(path / "quad.ply")
    mesh.write_ply(name)
    return name


@pytest.mark.parametrize("flip", [False, True])
@pytest.mark.parametrize("kind", ["rectangle", "disk"])
def test_a_flat_light_shines_along_its_normal(kind, flip):
    turn = T().translate([0, 3, 0]) @ T().rotate([1, 0, 0], 90) @ T().scale(0.5)  # faces -Y
    b = emitter_bounds(only_emitter(area({"type": kind, "to_world": turn,
                                          "flip_normals": flip})), 5.0)
    assert b.kind == FINITE
    assert b.axis == pytest.approx([0, 1 if flip else -1, 0], abs=1e-6)
    assert b.cone == ANGLE_MARGIN and b.spread == pytest.approx(math.pi / 2)
    assert b.center == pytest.approx([0, 3, 0], abs=1e-6)
    # a flat Lambertian emitter: peak intensity L A = Phi / pi
    a = 1.0 if kind == "rectangle" else math.pi * 0.25
    assert b.intensity == pytest.approx(2.0 * a, rel=1e-3)


@pytest.mark.parametrize("flip", [False, True])
def test_a_flat_mesh_light_shines_along_its_faces(tmp_path, flip):
    e = only_emitter(area({"type": "ply", "filename": quad_ply(tmp_path), "flip_normals": flip}))
    b = emitter_bounds(e, 5.0)
    assert b.axis == pytest.approx([0, -1 if flip else 1, 0], abs=1e-6)
    assert b.cone == pytest.approx(ANGLE_MARGIN, abs=1e-6)
    # and that is the side Mitsuba's own sampling says it emits to
    n = e.get_shape().sample_position(0.0, mi.Point2f(0.3, 0.6)).n
    assert float(n.y[0]) == pytest.approx(b.axis[1], abs=1e-6)


@pytest.mark.parametrize("shape", [{"type": "cube"}, {"type": "sphere"}])
def test_a_light_facing_every_way_has_no_cone(shape):
    b = emitter_bounds(only_emitter(area(shape)), 5.0)
    assert b.cone == math.pi


def test_a_point_light():
    b = emitter_bounds(only_emitter({"type": "point", "position": [1, 2, 3],
                                     "intensity": {"type": "rgb", "value": [5.0] * 3}}), 5.0)
    assert (b.kind, b.radius, b.cone) == (FINITE, 0.0, math.pi)
    assert b.center == pytest.approx([1, 2, 3])
    assert b.intensity == pytest.approx(5.0, rel=1e-5)


def test_a_spot_light_shines_into_its_cutoff_cone():
    e = only_emitter({"type": "spot", "cutoff_angle": 25.0, "beam_width": 20.0,
                      "to_world": T().look_at(origin=[0, 2, 0], target=[1, 0, 0], up=[0, 0, 1]),
                      "intensity": {"type": "rgb", "value": [3.0] * 3}})
    b = emitter_bounds(e, 5.0)
    assert b.center == pytest.approx([0, 2, 0], abs=1e-6)
    assert b.axis == pytest.approx(np.array([1, -2, 0]) / math.sqrt(5), abs=1e-6)
    assert b.cone == pytest.approx(math.radians(25.0) + ANGLE_MARGIN)
    assert b.spread == 0.0
    # the peak intensity is at least Phi over the cone's solid angle
    assert 0 < b.intensity <= 3.0 * (1 + 1e-3)


def test_lights_at_infinity_get_irradiances():
    env = emitter_bounds(only_emitter({"type": "constant",
                                       "radiance": {"type": "rgb", "value": [0.5] * 3}}), 1.0)
    # Mitsuba's power through the bounding disk, 4 pi^2 R^2 L, back to the irradiance pi L
    scene = mi.load_dict({"type": "scene", "ball": {"type": "sphere", "radius": 2.0},
                          "sky": {"type": "constant",
                                  "radiance": {"type": "rgb", "value": [0.5] * 3}},
                          "sun": {"type": "directional", "direction": [0, -1, 1],
                                  "irradiance": {"type": "rgb", "value": [4.0] * 3}}})
    radius = float(scene.bbox().bounding_sphere().radius)
    by_kind = {b.kind: b for b in (emitter_bounds(e, radius) for e in scene.emitters())}
    assert env.kind == ENVIRONMENT
    assert by_kind[ENVIRONMENT].intensity == pytest.approx(math.pi * 0.5, rel=1e-3)
    sun = by_kind[DIRECTIONAL]
    assert sun.intensity == pytest.approx(4.0, rel=1e-3)
    assert sun.axis == pytest.approx(np.array([0, -1, 1]) / math.sqrt(2), abs=1e-6)


@pytest.mark.parametrize("light, phi", [
    ({"type": "point", "intensity": {"type": "rgb", "value": [2.0] * 3}}, 8 * math.pi),
    (area({"type": "rectangle"}, 3.0), 3.0 * math.pi * 4.0),
])
def test_the_power_estimate_counts_a_constant_weight_once_per_sample(light, phi):
    """Mitsuba hands out one value for the weight of these lights' samples: the mean over the
    samples is still their power (4 pi I, pi L A)."""
    assert emitted_power(only_emitter(light)) == pytest.approx(phi, rel=1e-5)
