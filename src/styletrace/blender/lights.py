"""Blender lights -> Mitsuba emitters, with the unit conversions of `units`.

Point and spot lights are points (a radius only softens shadows in Cycles; the intensity far away is
the same); a spot's cone is Blender's full spot size; Cycles' blend (a smoothstep over the cosine)
becomes Mitsuba's linear ramp in angle (beam_width) that emits the same power (`spot_beam`;
tests/blender/test_units.py). Suns are directional (their angle is ignored). Area lights are Mitsuba
`rectangle`s or `disk`s turned to emit along the light's -Z, carrying an `area` emitter on a black
surface (unlike Cycles' lights, it blocks what reaches its back); ellipses become disks of the mean
diameter (with a warning). A Cycles light portal (an area light with `cycles.is_portal`) emits
nothing: it steers the sampling of the world towards a window, which changes the noise and not the
image. It becomes styletrace's `portal` emitter (kernel/portal.py) with the light's placement and
size, facing into the room along the light's -Z as in Cycles; a disk or ellipse portal becomes its
bounding rectangle (size_x by size_y; with a note), which only widens where samples are sent.
"""
from __future__ import annotations

import math

import numpy as np

from styletrace.blender import units

#: Mitsuba's rectangle and disk face +Z; Blender's area lights emit along -Z
TURN = np.diag([1.0, -1.0, -1.0, 1.0])
#: Mitsuba's spot shines along +Z; Blender's along -Z
SPOT = np.diag([-1.0, 1.0, -1.0, 1.0])


def _rgb(light, factor: float) -> dict:
    return {"type": "rgb", "value": tuple(float(c) * factor for c in light.color)}


def _unscaled_light(m: np.ndarray) -> np.ndarray:
    m = m.copy()
    for i in range(3):
        m[:3, i] /= np.linalg.norm(m[:3, i])
    return m


def _smoothstep(x: float) -> float:
    x = min(max(x, 0.0), 1.0)
    return x * x * (3.0 - 2.0 * x)


def _power(profile, half: float, steps: int = 400) -> float:
    """The power a spot of angular profile `profile(theta)` emits into its cone, up to a constant
    (midpoint rule)."""
    h = half / steps
    return sum(profile((i + 0.5) * h) * math.sin((i + 0.5) * h) for i in range(steps)) * h


def spot_beam(half: float, blend: float) -> float:
    """Mitsuba's beam_width (radians) for a Blender spot: the width at which Mitsuba's ramp emits
    the same power as Cycles' smoothstep blend (bisection).

    Cycles' attenuation is a smoothstep over the cosine, from the cone's edge to cos(half) +
    (1 - cos(half)) blend; Mitsuba's is linear in angle from beam_width to the edge.

    Args:
        half: the cone's half angle (radians). blend: Blender's spot blend, in [0, 1].

    Returns:
        The beam width, in radians (`half` where blend is 0).
    """
    if blend <= 0:
        return half
    c = math.cos(half)
    target = _power(lambda t: _smoothstep((math.cos(t) - c) / ((1.0 - c) * blend)), half)
    lo, hi = 0.0, half
    for _ in range(40):
        mid = (lo + hi) / 2
        ramp = lambda t, b=mid: 1.0 if t <= b else (half - t) / (half - b)  # noqa: E731
        lo, hi = (mid, hi) if _power(ramp, half) < target else (lo, mid)
    return (lo + hi) / 2


def is_portal(light) -> bool:
    """Whether a Blender light is a Cycles light portal.

    Args:
        light: a `bpy.types.Light` (its Cycles settings, where the Cycles add-on registered them).

    Returns:
        bool.
    """
    cycles = getattr(light, "cycles", None)
    return bool(getattr(cycles, "is_portal", False))


def convert_portal(light, matrix, warn) -> dict | None:
    """The `portal` emitter of a Cycles light portal: the area light's rectangle, turned so that
    its +z (the portal's side of the room) is the light's -Z; a disk or ellipse becomes its
    bounding rectangle, with a note.

    Args:
        light: the portal's light data (an area light). matrix: its placement, 4x4.
        warn: called with a note line (a round portal made rectangular, one of zero size left
            out).

    Returns:
        The emitter description; None for a portal of zero size (which would sample nothing).
    """
    m = np.array(matrix, dtype=np.float64)
    # as an area light's: the sizes times the object's scale along the light's x and y
    sx, sy = np.linalg.norm(m[:3, 0]), np.linalg.norm(m[:3, 1])
    size_y = light.size_y if light.shape in ("RECTANGLE", "ELLIPSE") else light.size
    hx, hy = light.size * sx / 2.0, size_y * sy / 2.0
    if not hx * hy > 0.0:
        warn(f"styletrace: light portal '{light.name}' has zero size "
             f"({2 * hx:.3g} x {2 * hy:.3g}): left out")
        return None
    if light.shape in ("DISK", "ELLIPSE"):
        warn(f"styletrace: light portal '{light.name}' is a {light.shape.lower()}: sampled "
             f"through its bounding rectangle ({2 * hx:.3g} x {2 * hy:.3g})")
    return {"type": "portal",
            "to_world": _unscaled_light(m) @ np.diag([hx, hy, 1.0, 1.0]) @ TURN}


def convert_light(light, matrix, warn) -> dict | None:
    """The emitter (or emitting shape) description of a `bpy.types.Light` (see the module doc).

    Args:
        light: the light's data. matrix: its placement, 4x4.
        warn: called with a warning line (an ellipse rendered as a disk, an unsupported type).

    Returns:
        The description, or None for an unsupported light type (left out, with a warning).
    """
    m = np.array(matrix, dtype=np.float64)
    kind = light.type
    if kind == "AREA" and is_portal(light):
        return convert_portal(light, m, warn)
    if kind == "POINT":
        return {"type": "point", "position": m[:3, 3].tolist(),
                "intensity": _rgb(light, units.point_intensity(light.energy))}
    if kind == "SPOT":
        half = light.spot_size / 2.0
        beam = spot_beam(half, light.spot_blend)
        return {"type": "spot", "to_world": _unscaled_light(m) @ SPOT,
                "cutoff_angle": math.degrees(half),
                "beam_width": math.degrees(min(beam, half)),
                "intensity": _rgb(light, units.point_intensity(light.energy))}
    if kind == "SUN":
        d = -m[:3, 2]
        return {"type": "directional", "direction": (d / np.linalg.norm(d)).tolist(),
                "irradiance": _rgb(light, units.sun_irradiance(light.energy))}
    if kind == "AREA":
        sx, sy = np.linalg.norm(m[:3, 0]), np.linalg.norm(m[:3, 1])
        size_x = light.size
        size_y = light.size_y if light.shape in ("RECTANGLE", "ELLIPSE") else light.size
        base = _unscaled_light(m)
        if light.shape in ("DISK", "ELLIPSE"):
            if light.shape == "ELLIPSE" and abs(size_x * sx - size_y * sy) > 1e-6:
                warn(
                    f"styletrace: area light '{light.name}' is an ellipse: rendered as a disk of "
                    "the mean diameter"
                )
            r = (size_x * sx + size_y * sy) / 4.0
            area = math.pi * r * r
            shape = {"type": "disk", "to_world": base @ np.diag([r, r, 1.0, 1.0]) @ TURN}
        else:
            hx, hy = size_x * sx / 2.0, size_y * sy / 2.0
            area = 4.0 * hx * hy
            shape = {"type": "rectangle", "to_world": base @ np.diag([hx, hy, 1.0, 1.0]) @ TURN}
        # Cycles' lights block no light; styletrace refuses emitters on see-through (null) surfaces,
        # so the light is a black, one-sided emitter that absorbs what reaches its back
        # (docs/blender.md)
        shape["bsdf"] = {
            "type": "diffuse",
            "reflectance": {"type": "rgb", "value": (0.0, 0.0, 0.0)},
        }
        shape["emitter"] = {
            "type": "area",
            "radiance": _rgb(light, units.area_radiance(light.energy, area)),
        }
        return shape
    warn(f"styletrace: light '{light.name}' of type {kind} is not supported: left out")
    return None
