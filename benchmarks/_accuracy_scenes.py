"""The three Blender scenes of benchmarks/accuracy.py, built with bpy from tests/blender/scenes.py's
helpers (`reset`, `material`, `plane`, `cube`, `sphere`, `light`, `camera`, `look`):

- `window`: tests/blender/scenes.py's `interior`, a room lit through a window by a sun and a sky,
  with a small area lamp on the ceiling;
- `lamps`: a closed room lit only by 20 small lamps of different colours and powers (16 points
  without a radius, 4 small area lights behind the camera), Principled materials;
- `still_life`: glossy metal (two spheres and a teapot-like pot) and a glass tumbler on a
  backdrop, under an area light and a float environment map (the tests' sky image).

Every builder takes the image's side in pixels and returns the scene (Standard view transform,
2 Cycles threads, single-part EXR output: `scenes.reset`).
"""
from __future__ import annotations

import math
import os
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
BLENDER_TESTS = os.path.join(os.path.dirname(HERE), "tests", "blender")
if BLENDER_TESTS not in sys.path:
    sys.path.insert(0, BLENDER_TESTS)

import bpy  # noqa: E402
import scenes as S  # noqa: E402  (tests/blender/scenes.py)


def principled(name: str, colour, roughness: float = 0.5, specular: float = 0.5,
               metallic: float = 0.0, transmission: float = 0.0, ior: float = 1.5):
    """A material of one Principled BSDF.

    Args:
        name: the material's name. colour: its Base Color (linear RGB). roughness, specular
            (Specular IOR Level), metallic, transmission (Transmission Weight), ior: its inputs.

    Returns:
        The `bpy.types.Material`.
    """
    return S.material(name, "ShaderNodeBsdfPrincipled", **{
        "Base Color": tuple(colour), "Roughness": roughness, "Specular IOR Level": specular,
        "Metallic": metallic, "Transmission Weight": transmission, "IOR": ior})[0]


def window(size: int = 128):
    """tests/blender/scenes.py's `interior` (its docstring): a room lit through a window.

    Args:
        size: the image's side in pixels.

    Returns:
        The scene.
    """
    return S.interior(size)


#: the lamps room's point lamps: (x, y, z, watts, colour); from hue to hue around the room, at
#: heights from a floor lamp's to a sconce's
POINTS = (
    (-2.6, 2.6, 0.4, 3.75, (1.0, 0.55, 0.25)),
    (-1.4, 2.6, 2.2, 7.5, (1.0, 0.85, 0.6)),
    (0.0, 2.6, 1.2, 2.0, (0.3, 0.5, 1.0)),
    (1.4, 2.6, 2.2, 7.5, (1.0, 0.85, 0.6)),
    (2.6, 2.6, 0.4, 3.0, (0.4, 1.0, 0.45)),
    (2.6, 1.2, 1.8, 6.25, (1.0, 0.3, 0.3)),
    (2.6, -0.4, 0.9, 1.5, (1.0, 1.0, 1.0)),
    (2.6, -2.0, 2.4, 10.0, (1.0, 0.75, 0.4)),
    (-2.6, 1.0, 1.8, 5.0, (0.6, 0.4, 1.0)),
    (-2.6, -0.6, 0.8, 2.5, (1.0, 0.9, 0.3)),
    (-2.6, -2.0, 2.4, 8.75, (0.5, 0.8, 1.0)),
    (-0.9, 0.8, 1.05, 0.75, (1.0, 0.6, 0.2)),
    (0.6, 0.0, 0.25, 1.0, (0.3, 1.0, 0.9)),
    (1.6, 1.6, 1.5, 4.5, (1.0, 0.45, 0.8)),
    (-1.8, -1.2, 1.4, 2.25, (0.9, 1.0, 0.5)),
    (0.2, -0.8, 2.6, 5.5, (1.0, 1.0, 0.85)),
)
#: the small area lights on the wall behind the camera, out of its view (Blender 5's Cycles hides
#: lights from the camera, styletrace's are emitting squares): (x, z, watts, colour), each facing
#: into the room and 20 degrees down
WALL = (
    (-2.2, 2.4, 6.25, (1.0, 0.9, 0.75)),
    (-0.8, 2.0, 3.75, (0.75, 0.85, 1.0)),
    (0.8, 2.6, 2.5, (1.0, 0.7, 0.5)),
    (2.2, 2.2, 5.0, (0.9, 1.0, 0.9)),
)


def lamps(size: int = 128):
    """A closed 6 x 6 x 3 m room, no sky, lit only by `POINTS` (points: no radius, so that both
    renderers' lamps are points) and `WALL` (0.2 m squares on the wall behind the camera); a sofa,
    a table, shelves and balls of Principled materials, a glossy floor.

    Args:
        size: the image's side in pixels.

    Returns:
        The scene.
    """
    s = S.reset(size)
    wall = principled("wall", (0.7, 0.68, 0.62), roughness=0.9)
    floor = principled("floor", (0.35, 0.22, 0.12), roughness=0.3)
    ceiling = principled("ceiling", (0.8, 0.8, 0.8), roughness=0.95)
    sofa = principled("sofa", (0.5, 0.12, 0.1), roughness=0.85)
    table = principled("table", (0.6, 0.45, 0.3), roughness=0.4)
    shelf = principled("shelf", (0.25, 0.3, 0.35), roughness=0.6)
    ball = principled("ball", (0.8, 0.8, 0.75), roughness=0.2)
    brass = principled("brass", (0.9, 0.7, 0.4), roughness=0.3, metallic=1.0)
    S.plane(6, (0, 0, 0), mat=floor)
    S.plane(6, (0, 0, 3), (math.pi, 0, 0), mat=ceiling)
    S.plane(6, (0, 3, 1.5), (math.pi / 2, 0, 0), mat=wall)
    S.plane(6, (0, -3, 1.5), (-math.pi / 2, 0, 0), mat=wall)
    S.plane(6, (-3, 0, 1.5), (0, math.pi / 2, 0), mat=wall)
    S.plane(6, (3, 0, 1.5), (0, -math.pi / 2, 0), mat=wall)
    S.cube(1.0, (-2.2, 1.2, 0.4), mat=sofa).scale = (1.0, 2.2, 0.8)
    S.cube(1.0, (-0.9, 0.8, 0.45), mat=table).scale = (1.0, 0.8, 0.9)
    S.cube(1.0, (2.6, 0.8, 1.0), mat=shelf).scale = (0.6, 1.6, 2.0)
    S.sphere(0.3, (0.6, 0.9, 0.3), mat=ball)
    S.sphere(0.2, (-0.7, 0.6, 1.1), mat=brass)
    S.sphere(0.25, (1.2, -0.3, 0.25), mat=brass)
    for x, y, z, watts, colour in POINTS:
        S.light("POINT", (x, y, z), energy=watts, color=colour, shadow_soft_size=0.0)
    for x, z, watts, colour in WALL:
        S.light("AREA", (x, -2.95, z), (math.radians(70), 0, 0), energy=watts, color=colour,
                size=0.2)
    eye = (0.2, -2.8, 1.6)
    S.camera(eye, S.look(eye, (0.0, 1.5, 0.9)), lens=18)
    return s


#: the glass tumbler's base above the floor, in metres (`still_life`'s docstring says why)
TUMBLER_GAP = 0.002


def still_life(size: int = 128):
    """Glossy metal and glass on a backdrop: a gold sphere (Principled Metallic 1, Roughness
    0.15), a rough copper sphere (0.4), a steel pot with a spout, a handle and a lid knob (0.25),
    a glass tumbler (Transmission Weight 1, Roughness 0, IOR 1.45) and a glass ball, on a floor
    and a wall of diffuse grey; an area light above the front left (out of view) and the tests'
    float sky map (`scenes.world_texture`) at strength 0.25.

    The tumbler stands TUMBLER_GAP above the floor. With its base in the floor's plane, Cycles
    (Blender 5.0) draws the tumbler's top and base dark where styletrace draws the floor seen
    through the glass (as both renderers do with the gap, and as styletrace does without it): the
    two renderers' converged images then differ there, and the comparison of their errors, each
    against its own converged image, would compare two different images. Measured at 96 x 96
    (Cycles 256 samples, styletrace 1024): the tumbler's pixels agree with the gap and differ
    without it; the rest of the image agrees either way.

    Args:
        size: the image's side in pixels.

    Returns:
        The scene.
    """
    s = S.reset(size)
    backdrop = principled("backdrop", (0.55, 0.55, 0.52), roughness=0.8, specular=0.3)
    gold = principled("gold", (1.0, 0.77, 0.34), roughness=0.15, metallic=1.0)
    copper = principled("copper", (0.95, 0.64, 0.54), roughness=0.4, metallic=1.0)
    steel = principled("steel", (0.75, 0.75, 0.78), roughness=0.25, metallic=1.0)
    glass = principled("glass", (1.0, 1.0, 1.0), roughness=0.0, transmission=1.0, ior=1.45)
    S.plane(12, (0, 0, 0), mat=backdrop)
    S.plane(12, (0, 3, 3), (math.pi / 2, 0, 0), mat=backdrop)
    S.sphere(0.45, (-1.3, 0.4, 0.45), mat=gold)
    S.sphere(0.3, (1.5, -0.4, 0.3), mat=copper)
    # the pot: a squat body, a spout, a handle and a knob
    body = S.sphere(0.6, (0.2, 0.9, 0.45), mat=steel)
    body.scale = (1.0, 1.0, 0.75)
    bpy.ops.mesh.primitive_cone_add(radius1=0.12, radius2=0.05, depth=0.6,
                                    location=(0.9, 0.9, 0.65), rotation=(0, math.radians(55), 0))
    S.add(bpy.context.object, steel)
    bpy.ops.mesh.primitive_torus_add(major_radius=0.28, minor_radius=0.05,
                                     location=(-0.45, 0.9, 0.55), rotation=(math.pi / 2, 0, 0))
    bpy.ops.object.shade_smooth()
    S.add(bpy.context.object, steel)
    S.sphere(0.08, (0.2, 0.9, 0.95), mat=steel)
    bpy.ops.mesh.primitive_cylinder_add(radius=0.25, depth=0.7,
                                        location=(0.5, -0.7, 0.35 + TUMBLER_GAP))
    S.add(bpy.context.object, glass)
    S.sphere(0.22, (-0.5, -0.9, 0.22), mat=glass)
    S.world_texture(0.25)
    S.light("AREA", (-2.5, -2.5, 4.0), (math.radians(40), 0, math.radians(-45)), energy=150.0,
            size=1.5)
    eye = (0.0, -4.2, 1.5)
    S.camera(eye, S.look(eye, (0.0, 0.2, 0.45)), lens=42)
    return s


SCENES = {"window": window, "lamps": lamps, "still_life": still_life}


def source_files() -> tuple[str, ...]:
    """The files whose text decides the scenes (this module and tests/blender/scenes.py), for
    cache keys.

    Returns:
        Their paths.
    """
    return (os.path.abspath(__file__), os.path.join(BLENDER_TESTS, "scenes.py"))
