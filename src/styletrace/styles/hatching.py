"""hatching: cross-hatching by slabs around planes through the view direction (supplement S5.6).

Reference: "An Illustration Technique Using Hardware-Based Intersections and Skeletons",
Oliver Deussen, Joerg Hamel, Andreas Raab, Stefan Schlechtweg, Thomas Strothotte (1999).

Parameters
- sets (int, default 3, in [1, 8]): number of hatching directions n
- spacing (float, default 0.04, > 0): distance between neighbouring planes of a set, in scene units
- thickness (float, default 0.3 * spacing, in (0, spacing)): line thickness d
- angle (float, default 45): rotation of the first set around the view direction, in degrees
- u_min (float, default 0.05), u_max (float, default 0.9, > u_min): brightness of full / no hatching
- line_color (colour, default 0.05,0.05,0.08), background (colour, default 0.97,0.95,0.9)

Set j (j = 0..n-1) is the family of parallel planes {x : x . n_j = k spacing, k integer} whose unit normal
    n_j = cos(theta_j) e1 + sin(theta_j) e2,   theta_j = angle + j pi / n,
with (e1, e2) an orthonormal basis perpendicular to the camera's view direction (e2 the camera's up
vector made perpendicular): every plane contains the view direction, so n_i x n_j is parallel to it.
The planes pass through the world origin (o = 0). With u = (r+g+b)/3 of the inner estimate <I>,
    m = floor((1 - clamp((u - u_min) / (u_max - u_min), 0, 1)) n + 1/2)      (m = 0 at u_max, n at u_min)
sets 0..m-1 are active, and the vertex p is on a line when, for some active j,
    dist_j = |frac(p . n_j / spacing + 1/2) - 1/2| spacing < d / 2
(the distance to the nearest plane of set j). g = line_color on a line, background elsewhere.
`hatch_mask` is that predicate on Dr.Jit arrays; the camera is read in `prepare` (until then the
camera of Mitsuba's default sensor is assumed: looking along +z, up +y).
"""
from __future__ import annotations

import math
from typing import Sequence

import drjit as dr
import mitsuba as mi

from .base import Param, Style, StyleError, Vertex, brightness, camera, camera_forward
from .registry import register

Vec = tuple[float, float, float]


def camera_up(scene: mi.Scene) -> Vec:
    """World-space up vector of the scene's first sensor (its local +y); +y if there is none."""
    return camera(scene).up


def _cross(a: Sequence[float], b: Sequence[float]) -> Vec:
    return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])


def _unit(a: Sequence[float]) -> Vec:
    n = math.sqrt(sum(x * x for x in a))
    return tuple(x / n for x in a)


def plane_normals(view: Sequence[float], up: Sequence[float], sets: int, angle_deg: float) -> list[Vec]:
    """Unit normals n_j perpendicular to `view`, at angles angle + j pi / sets around it."""
    f = _unit(view)
    d = sum(a * b for a, b in zip(up, f))
    e2 = tuple(a - d * b for a, b in zip(up, f))
    if math.sqrt(sum(x * x for x in e2)) < 1e-6:  # up parallel to view: any perpendicular will do
        helper = (1.0, 0.0, 0.0) if abs(f[0]) < 0.9 else (0.0, 1.0, 0.0)
        e2 = _cross(f, helper)
    e2 = _unit(e2)
    e1 = _unit(_cross(e2, f))
    out = []
    for j in range(sets):
        t = math.radians(angle_deg) + j * math.pi / sets
        c, s = math.cos(t), math.sin(t)
        out.append(tuple(c * a + s * b for a, b in zip(e1, e2)))
    return out


def coverage(u: mi.Float, u_min: float, u_max: float) -> mi.Float:
    """1 - clamp((u - u_min) / (u_max - u_min), 0, 1): 1 at (or below) u_min, 0 at (or above) u_max."""
    return 1.0 - dr.clip((u - u_min) * (1.0 / (u_max - u_min)), 0.0, 1.0)


def active_sets(u: mi.Float, sets: int, u_min: float, u_max: float) -> mi.Float:
    """m = floor(coverage(u) sets + 1/2), an integer-valued Float in {0..sets}."""
    return dr.floor(coverage(u, u_min, u_max) * sets + 0.5)


def hatch_mask(p: mi.Point3f, u: mi.Float, normals: Sequence[Sequence[float]], spacing: float,
               thickness: float, u_min: float = 0.05, u_max: float = 0.9) -> mi.Bool:
    """True where p lies within thickness/2 of a plane of one of the m(u) active sets (see module doc)."""
    m = active_sets(u, len(normals), u_min, u_max)
    hit = dr.zeros(mi.Bool, dr.width(p))
    for j, nj in enumerate(normals):
        s = dr.dot(mi.Vector3f(p), mi.Vector3f(*nj)) * (1.0 / spacing) + 0.5
        dist = dr.abs(s - dr.floor(s) - 0.5) * spacing
        hit |= (dist < 0.5 * thickness) & (m > j)
    return hit


@register
class Hatching(Style):
    name = "hatching"
    summary = "cross-hatching: brightness picks how many plane sets around the view direction draw lines"
    params = (
        Param("sets", "int", 3, "number of hatching directions", low=1, high=8),
        Param("spacing", "float", 0.04, "distance between planes (scene units)", low=0.0, low_open=True),
        Param("thickness", "float", None, "line thickness d (default 0.3 * spacing), < spacing",
              low=0.0, low_open=True),
        Param("angle", "float", 45.0, "rotation of the first set around the view direction (degrees)"),
        Param("u_min", "float", 0.05, "brightness at and below which all sets are drawn"),
        Param("u_max", "float", 0.9, "brightness at and above which no set is drawn"),
        Param("line_color", "color", (0.05, 0.05, 0.08), "colour of the lines", low=0.0),
        Param("background", "color", (0.97, 0.95, 0.9), "colour between the lines", low=0.0),
    )
    default_inner = 16

    def __init__(self, **values):
        super().__init__(**values)
        self.set_camera((0.0, 0.0, 1.0), (0.0, 1.0, 0.0))

    def validate(self) -> None:
        if self.thickness is None:
            self.values["thickness"] = 0.3 * self.spacing
        if not self.thickness < self.spacing:
            raise StyleError(f"bad value {self.thickness:g} for parameter 'thickness': must be less than "
                             f"spacing = {self.spacing:g}")
        if not self.u_max > self.u_min:
            raise StyleError(f"bad value {self.u_max:g} for parameter 'u_max': must exceed u_min = {self.u_min:g}")

    def set_camera(self, view: Sequence[float], up: Sequence[float]) -> None:
        self.view = tuple(float(x) for x in view)
        self.normals = plane_normals(self.view, up, self.sets, self.angle)

    def prepare(self, scene: mi.Scene) -> None:
        self.set_camera(camera_forward(scene), camera_up(scene))

    def apply(self, I: mi.Color3f, v: Vertex) -> mi.Color3f:
        line = hatch_mask(v.p, brightness(I), self.normals, self.spacing, self.thickness, self.u_min, self.u_max)
        return dr.select(line, mi.Color3f(*self.line_color), mi.Color3f(*self.background))
