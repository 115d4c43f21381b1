"""halftone: dots of brightness-dependent radius on a 3D grid (supplement S5.6).

Reference: "Non-photorealistic Rendering by Q-mapping", Peter Hall (1999).

Parameters
- spacing (float, default 0.05, > 0): grid interval d, in scene units; grid points are k d, k in Z^3
- max_radius_fraction (float, default 0.75, in (0, 1]): the darkest dot radius as a fraction of
  sqrt(3) d / 2 (half the cell diagonal, the radius at which the spheres cover all space):
  r_max = max_radius_fraction sqrt(3) d / 2
- u_min (float, default 0.05), u_max (float, default 0.9, > u_min): brightness of the largest / no dot
- dark (colour, default 0.1,0.1,0.15), light (colour, default 0.97,0.95,0.9)

With u = (r+g+b)/3 of the inner estimate <I> and the vertex position p:
    g_p = round(p / d) d                                       (nearest grid point, per component)
    r   = (1 - clamp((u - u_min) / (u_max - u_min), 0, 1)) r_max
    g(<I>) = dark if |p - g_p| < r else light
`halftone_mask` is that predicate on Dr.Jit arrays.
"""
from __future__ import annotations

import math

import drjit as dr
import mitsuba as mi

from .base import Param, Style, StyleError, Vertex, brightness
from .hatching import coverage
from .registry import register


def dot_radius(u: mi.Float, r_max: float, u_min: float = 0.05, u_max: float = 0.9) -> mi.Float:
    """r = (1 - clamp((u - u_min) / (u_max - u_min), 0, 1)) r_max."""
    return coverage(u, u_min, u_max) * r_max


def halftone_mask(p: mi.Point3f, u: mi.Float, spacing: float, r_max: float,
                  u_min: float = 0.05, u_max: float = 0.9) -> mi.Bool:
    """True where p is closer than r(u) to its nearest grid point (see module doc)."""
    g = dr.round(mi.Vector3f(p) * (1.0 / spacing)) * spacing
    r = dot_radius(u, r_max, u_min, u_max)
    return dr.squared_norm(mi.Vector3f(p) - g) < r * r


@register
class Halftone(Style):
    name = "halftone"
    summary = "half-tone: dark dots on a 3D grid, radius growing as brightness falls"
    params = (
        Param("spacing", "float", 0.05, "grid interval d (scene units)", low=0.0, low_open=True),
        Param("max_radius_fraction", "float", 0.75, "largest radius as a fraction of sqrt(3) d / 2",
              low=0.0, high=1.0, low_open=True),
        Param("u_min", "float", 0.05, "brightness at and below which dots are largest"),
        Param("u_max", "float", 0.9, "brightness at and above which dots vanish"),
        Param("dark", "color", (0.1, 0.1, 0.15), "colour inside the dots", low=0.0),
        Param("light", "color", (0.97, 0.95, 0.9), "colour outside the dots", low=0.0),
    )
    default_inner = 16

    def validate(self) -> None:
        if not self.u_max > self.u_min:
            raise StyleError(f"bad value {self.u_max:g} for parameter 'u_max': must exceed u_min = {self.u_min:g}")

    @property
    def r_max(self) -> float:
        return self.max_radius_fraction * 0.5 * math.sqrt(3.0) * self.spacing

    def apply(self, I: mi.Color3f, v: Vertex) -> mi.Color3f:
        dot = halftone_mask(v.p, brightness(I), self.spacing, self.r_max, self.u_min, self.u_max)
        return dr.select(dot, mi.Color3f(*self.dark), mi.Color3f(*self.light))
