"""xtoon: X-Toon, a toon shader with a "tone detail" axis, in closed form (supplement S5.6), after
Barla, Thollot, Markosian, "X-Toon: An Extended Toon Shader" (2006).

Parameters
- light_dir (vector, default auto): direction towards the light; auto as in `gooch`
- mode (choice orientation|depth, default orientation): the detail attribute
- r (float, default 2, >= 0): exponent of the orientation mode (larger: thinner rim)
- z_min (float, default auto, > 0), z_max (float, default auto, > z_min): the depth mode's range
- gradient (gradient, default a 3-band warm ramp over tone in [0, 1]): G, clamped at its end stops
- detail_color (colour, default 0.95,0.92,0.85): colour at zero detail

g = D G(n.l) + (1 - D) detail_color, ignoring the estimate; docs/design/closed_form_styles.md.
"""
from __future__ import annotations

import math

from styletrace.gate import dr, mi
from styletrace.styles.base import Param, Style, StyleError, Vertex, camera, increasing
from styletrace.styles.gooch import AUTO_LIGHT, CameraLight, facing
from styletrace.styles.gradient import Gradient
from styletrace.styles.registry import register_style

#: three flat bands (dark brown, terracotta, warm sand) with narrow linear transitions
BANDS = "0:#4a2c2a;0.32:#4a2c2a;0.34:#b5563a;0.64:#b5563a;0.66:#f4c98b;1:#f4c98b"


def camera_position(scene: mi.Scene) -> tuple[float, float, float]:
    """World-space position of the scene's first sensor (origin if there is none).

    Args:
        scene: a loaded mi.Scene.

    Returns:
        (x, y, z).
    """
    return camera(scene).position


@register_style
class XToon(CameraLight, Style):
    """The xtoon style (the module doc).

    Args:
        **values: its parameters (the module doc), as `Style` takes them.

    Raises:
        StyleError: a bad value, or z_max <= z_min.
    """

    name = "xtoon"
    summary = ("X-Toon: toon ramp over n.l faded by an orientation or depth detail, closed form "
               "(Barla et al. 2006)")
    params = (
        Param(
            "light_dir", "vector", None, "direction towards the light (normalised)", auto=AUTO_LIGHT
        ),
        Param(
            "mode", "choice", "orientation", "detail attribute", choices=("orientation", "depth")
        ),
        Param("r", "float", 2.0, "orientation exponent: D = |n.wo|^r", low=0.0),
        Param(
            "z_min",
            "float",
            None,
            "depth of full detail (depth mode)",
            low=0.0,
            low_open=True,
            auto="depth mode: the 5% quantile of the first hits' camera depth (unresolved: 1)",
        ),
        Param(
            "z_max",
            "float",
            None,
            "depth of zero detail (depth mode)",
            low=0.0,
            low_open=True,
            auto="depth mode: the 95% quantile of the first hits' camera depth (unresolved: 10)",
        ),
        Param("gradient", "gradient", Gradient.parse(BANDS), "toon colours over tone n.l"),
        Param("detail_color", "color", (0.95, 0.92, 0.85), "colour at zero detail", low=0.0),
    )
    default_inner = 0

    def __init__(self, **values):
        super().__init__(**values)
        self.camera = (0.0, 0.0, 0.0)

    def validate(self) -> None:
        lo, hi = self.depth_range()
        if not hi > lo:
            raise StyleError(f"bad value {hi:g} for parameter 'z_max': must exceed z_min = {lo:g}")

    def depth_range(self) -> tuple[float, float]:
        """(z_min, z_max) in use; an unresolved auto end is 1 or 10 (the other end times or over 10
        where only one is given)."""
        lo, hi = self.z_min, self.z_max
        if lo is None:
            lo = 1.0 if hi is None else min(1.0, hi / 10)
        if hi is None:
            hi = max(10.0, lo * 10)
        return lo, hi

    def auto_values(self, facts) -> dict:
        out = super().auto_values(facts)
        if self.mode == "depth" and (self.z_min is None or self.z_max is None):
            lo, hi = increasing(facts.depth([0.05, 0.95]))
            lo = max(lo, 1e-6) if self.z_min is None else self.z_min
            hi = hi if self.z_max is None else self.z_max
            if not hi > lo:  # one end given beyond the scene's depth range: keep a decade
                lo, hi = (lo, lo * 10) if self.z_max is None else (hi / 10, hi)
            out.update({k: v for k, v in (("z_min", lo), ("z_max", hi))
                        if self.values[k] is None})
        return out

    def prepare(self, scene: mi.Scene) -> None:
        self.camera = camera_position(scene)
        self.read_light(scene)

    def detail(self, n: mi.Vector3f, v: Vertex) -> mi.Float:
        """D in [0, 1] for the unit, viewer-facing normal n: |n.wo|^r (orientation), or
        1 - log(z / z_min) / log(z_max / z_min), z the clamped camera depth (depth).

        Args:
            n: unit, viewer-facing normals (mi.Vector3f); v: the vertices (`Vertex`).

        Returns:
            mi.Float.
        """
        if self.mode == "orientation":
            return dr.power(dr.clip(dr.abs(dr.dot(n, v.wo)), 0.0, 1.0), self.r)
        z = dr.dot(v.p - mi.Point3f(*self.camera), v.view)
        z_min, z_max = self.depth_range()
        z = dr.clip(z, z_min, z_max)
        return 1.0 - dr.log(z * (1.0 / z_min)) * (1.0 / math.log(z_max / z_min))

    def apply(self, I: mi.Color3f, v: Vertex) -> mi.Color3f:
        n = facing(v.n, v.wo)
        tone = dr.dot(n, mi.Vector3f(*self.light()))
        D = self.detail(n, v)
        return dr.lerp(mi.Color3f(*self.detail_color), self.gradient.eval(tone), D)
