"""cel: global-illumination cel shading (supplement S5.2).

Parameters
- thresholds (floats, default 0.75): increasing brightness steps t_1 < ... < t_K
- levels (floats, default 0.4,0.95): K+1 target brightnesses m_0..m_K

With u = (r+g+b)/3 of the inner estimate <I>, the target brightness is
    u' = m(u) = m_j  where j = number of thresholds t_i <= u,
and the output keeps the colour of global illumination:
    g(<I>) = <I> u' / u          (grey (u',u',u') where u <= 0, since <I> has no colour there).
"""
from __future__ import annotations

import drjit as dr
import mitsuba as mi

from .base import Param, Style, StyleError, Vertex, brightness
from .registry import register


@register
class Cel(Style):
    name = "cel"
    summary = "GI cel shading: brightness quantized to levels, colour kept (S5.2)"
    params = (
        Param("thresholds", "floats", (0.75,), "brightness steps between levels, increasing"),
        Param("levels", "floats", (0.4, 0.95), "target brightness of each band (one more than thresholds)", low=0.0),
    )
    default_inner = 16

    def validate(self) -> None:
        t, m = self.thresholds, self.levels
        if any(b <= a for a, b in zip(t, t[1:])):
            raise StyleError(f"bad value {','.join(map(str, t))!r} for parameter 'thresholds': must increase")
        if len(m) != len(t) + 1:
            raise StyleError(f"bad value {','.join(map(str, m))!r} for parameter 'levels': "
                             f"expected {len(t) + 1} levels for {len(t)} thresholds")

    def target(self, u: mi.Float) -> mi.Float:
        out = mi.Float(self.levels[0])
        for t, m in zip(self.thresholds, self.levels[1:]):
            out = dr.select(u >= t, m, out)
        return out

    def apply(self, I: mi.Color3f, v: Vertex) -> mi.Color3f:
        u = brightness(I)
        target = self.target(u)
        return dr.select(u > 0, I * (target / dr.maximum(u, 1e-30)), mi.Color3f(target))
