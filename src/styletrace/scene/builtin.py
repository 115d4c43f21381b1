"""Built-in scenes, as Mitsuba scene dictionaries.

- `cornell-box` (default): Mitsuba's Cornell box.
- `dragon`: the bundled scanned dragon on a ground plane under two area lights and a dim sky.
- `mixed`: the dragon scene with per-object styles (cel dragon, hatched floor, glass sphere).
- `lines`: the dragon with a mirror behind and a glass sphere in front (docs/lines.md).
- `furnace`: a diffuse sphere of albedo rho under a constant environment E (exitant rho*E).

All use the `owen_sobol` sampler (`config.choices.SAMPLER_DEFAULT`; `scene.loading.scene_dict(...,
sampler=...)` picks another) and a box pixel filter (docs/design/builtin_scenes.md).
"""
from __future__ import annotations

from importlib import resources
from typing import Any, Callable

from styletrace.config.choices import SAMPLER_DEFAULT as SAMPLER
from styletrace.gate import mi

FURNACE_ALBEDO = (0.8, 0.5, 0.3)
FURNACE_RADIANCE = 1.0


def _film(width: int, height: int) -> dict[str, Any]:
    return {"type": "hdrfilm", "width": width, "height": height, "rfilter": {"type": "box"},
            "pixel_format": "rgb", "component_format": "float32"}


def _sensor(origin, target, fov: float, width: int, height: int, up=(0, 1, 0)) -> dict[str, Any]:
    return {"type": "perspective", "fov": fov, "fov_axis": "smaller",
            "to_world": mi.ScalarTransform4f().look_at(origin=origin, target=target, up=up),
            "sampler": {"type": SAMPLER, "sample_count": 16}, "film": _film(width, height)}


def cornell_box(width: int = 256, height: int = 256) -> dict[str, Any]:
    """Mitsuba's Cornell box without its integrator, with this module's film and sampler.

    Args:
        width, height: the film's size in pixels.

    Returns:
        The scene dict.
    """
    scene = mi.cornell_box()
    scene.pop("integrator", None)
    scene["sensor"]["film"] = _film(width, height)
    scene["sensor"]["sampler"] = {"type": SAMPLER, "sample_count": 16}
    return scene


def dragon_mesh_path() -> str:
    return str(resources.files("styletrace.assets").joinpath("welsh-dragon-22k.ply"))


def dragon_to_world() -> mi.ScalarTransform4f:
    """Scan coordinates (z up, far from the origin) -> unit height, y up, feet at y = 0, centred."""
    lo = (-44.6832, -749.343, 235.922)
    hi = (23.7925, -594.237, 360.499)
    s = 1.0 / (hi[2] - lo[2])
    cx, cy = 0.5 * (lo[0] + hi[0]), 0.5 * (lo[1] + hi[1])
    T = mi.ScalarTransform4f
    # rotate(x, -90deg) sends +z to +y and +y to -z
    return (T().scale(s) @ T().rotate([1, 0, 0], -90.0) @ T().translate([-cx, -cy, -lo[2]]))


def dragon(width: int = 256, height: int = 256) -> dict[str, Any]:
    """The bundled scanned dragon (unit height) on a ground plane under two area lights and a dim
    sky.

    Args:
        width, height: the film's size in pixels.

    Returns:
        The scene dict.
    """
    T = mi.ScalarTransform4f
    light = {"type": "area", "radiance": {"type": "rgb", "value": [7.0, 6.6, 6.0]}}
    return {
        "type": "scene",
        "sensor": _sensor(
            origin=[2.6, 1.25, 1.1], target=[0.0, 0.45, 0.0], fov=32.0, width=width, height=height
        ),
        "dragon": {
            "type": "ply",
            "filename": dragon_mesh_path(),
            "to_world": dragon_to_world(),
            "bsdf": {"type": "diffuse", "reflectance": {"type": "rgb", "value": [0.8, 0.62, 0.45]}},
        },
        "ground": {
            "type": "rectangle",
            "to_world": T().rotate([1, 0, 0], -90.0) @ T().scale(6.0),
            "bsdf": {
                "type": "diffuse",
                "reflectance": {"type": "rgb", "value": [0.55, 0.55, 0.58]},
            },
        },
        "key_light": {
            "type": "rectangle",
            "to_world": T().translate([0.6, 2.4, 0.6])
            @ T().rotate([1, 0, 0], 90.0)
            @ T().scale(0.6),
            "emitter": light,
        },
        "fill_light": {
            "type": "rectangle",
            "to_world": T().translate([-0.8, 2.6, -0.6])
            @ T().rotate([1, 0, 0], 90.0)
            @ T().scale(0.5),
            "emitter": {"type": "area", "radiance": {"type": "rgb", "value": [3.0, 3.2, 3.6]}},
        },
        "sky": {"type": "constant", "radiance": {"type": "rgb", "value": [0.12, 0.14, 0.18]}},
    }


def mixed(width: int = 256, height: int = 256) -> dict[str, Any]:
    """The dragon scene with per-object styles: a cel-shaded dragon, a cross-hatched floor and a
    physically based glass sphere in front of the dragon (render with stylize=first_object_hit to
    see the dragon stylized through the glass too).

    Args:
        width, height: the film's size in pixels.

    Returns:
        The scene dict.
    """
    scene = dragon(width, height)
    scene["dragon"]["bsdf"] = {
        "type": "styled",
        "style": "cel",
        "thresholds": "0.3,0.6",
        "levels": "0.15,0.45,0.9",
        "inner_samples": 16,
        "bsdf": scene["dragon"]["bsdf"],
    }
    scene["ground"]["bsdf"] = {
        "type": "styled",
        "style": "hatching",
        "spacing": 0.03,
        "inner_samples": 8,
        "bsdf": scene["ground"]["bsdf"],
    }
    scene["glass"] = {"type": "sphere", "center": [0.8, 0.22, -0.1], "radius": 0.2,
                      "bsdf": {"type": "dielectric", "int_ior": 1.5}}
    return scene


def lines(width: int = 256, height: int = 256) -> dict[str, Any]:
    """The dragon scene with a standing mirror behind the dragon and a glass sphere in front of it:
    feature lines (`--lines --set line_depth=3`) show in the reflection and through the glass
    (docs/lines.md).

    Args:
        width, height: the film's size in pixels.

    Returns:
        The scene dict.
    """
    T = mi.ScalarTransform4f
    scene = dragon(width, height)
    scene["mirror"] = {
        "type": "rectangle",
        "to_world": T().look_at(origin=[-0.75, 0.62, -0.75], target=[1.4, 0.55, 1.2], up=[0, 1, 0])
        @ T().scale([0.75, 0.6, 1.0]),
        "bsdf": {"type": "conductor", "material": "Ag"},
    }
    scene["glass"] = {"type": "sphere", "center": [0.75, 0.22, 0.15], "radius": 0.2,
                      "bsdf": {"type": "dielectric", "int_ior": 1.5}}
    return scene


def furnace(width: int = 64, height: int = 64, albedo=FURNACE_ALBEDO,
            radiance: float = FURNACE_RADIANCE) -> dict[str, Any]:
    """A diffuse unit sphere under a constant environment: every first hit's exitant radiance is
    albedo * radiance exactly.

    Args:
        width, height: the film's size in pixels.
        albedo: the sphere's RGB reflectance rho; radiance: the environment's grey radiance E.

    Returns:
        The scene dict.
    """
    return {
        "type": "scene",
        "sensor": _sensor(
            origin=[0, 0, 4.0], target=[0, 0, 0], fov=35.0, width=width, height=height
        ),
        "sphere": {
            "type": "sphere",
            "radius": 1.0,
            "bsdf": {"type": "diffuse", "reflectance": {"type": "rgb", "value": list(albedo)}},
        },
        "env": {"type": "constant", "radiance": {"type": "rgb", "value": [radiance] * 3}},
    }


def scaled(scene: dict[str, Any], factor: float, light: float = 1.0) -> dict[str, Any]:
    """A scene dict scaled about the origin, camera included; with light = 1 the image is the same
    in other units (radiance is scale-free): the test of scene-relative style defaults. Shapes get
    a scale before their `to_world` (spheres: centre and radius); a perspective or thinlens sensor
    moves its position (Mitsuba refuses scale in a camera transform), scales its clip and focus
    distances, and keeps its orientation and field of view.

    Args:
        scene: the scene dict (left unchanged); factor: the scale.
        light: the factor on every area emitter's RGB radiance.

    Returns:
        The scaled copy.
    """
    T = mi.ScalarTransform4f

    def visit(node):
        if not isinstance(node, dict):
            return node
        out = {k: visit(v) for k, v in node.items()}
        kind = out.get("type")
        if kind in ("perspective", "thinlens"):
            m = mi.ScalarMatrix4f(out.get("to_world", T()).matrix)
            for i in range(3):
                m[i, 3] *= factor
            out["to_world"] = T(m)
            for key in ("near_clip", "far_clip", "focus_distance"):
                if key in out:
                    out[key] = factor * out[key]
        elif "to_world" in out:
            out["to_world"] = T().scale(factor) @ out["to_world"]
        if kind == "sphere":
            out["center"] = [factor * c for c in out.get("center", [0, 0, 0])]
            out["radius"] = factor * out.get("radius", 1.0)
        if kind == "area" and isinstance(out.get("radiance"), dict):
            out["radiance"] = {**out["radiance"],
                               "value": [light * v for v in out["radiance"]["value"]]}
        return out

    return visit(scene)


BUILTIN: dict[str, Callable[..., dict[str, Any]]] = {
    "cornell-box": cornell_box,
    "dragon": dragon,
    "furnace": furnace,
    "mixed": mixed,
    "lines": lines,
}
DEFAULT = "cornell-box"
