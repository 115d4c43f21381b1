"""cel: global-illumination cel shading (supplement S5.2).

Parameters
- thresholds (floats, default auto): increasing brightness steps t_1 < ... < t_K
- levels (floats, default 0.4,0.95): K+1 target brightnesses m_0..m_K

Auto thresholds (scene-relative, `scene.defaults`): the brightness quantiles 1/(K+1), ...,
K/(K+1) of what the camera sees of the objects this style covers, from a pilot of Mitsuba's `path`
integrator (32 cells along the film, 16 samples each, brightness averaged per cell), so the K+1 bands
hold about equal shares of the image whatever the scene's light level. A fixed brightness cannot: on
Mitsuba's test scenes the old default 0.75 put 87-92% of the pixels in one band. The chosen values are
printed (`styletrace render` logs them unless -q) and can be pinned with `thresholds=...`. A style that
was never resolved (rendered by calling mi.render directly) uses evenly spaced k/(K+1), i.e. 0.5.

With u = (r+g+b)/3 of the inner estimate <I>, the target brightness is
    u' = m(u) = m_j  where j = number of thresholds t_i <= u,
and the output keeps the colour of global illumination:
    g(<I>) = <I> u' / u          (grey (u',u',u') where u <= 0, since <I> has no colour there).
"""
from __future__ import annotations

import drjit as dr
import mitsuba as mi

from .base import Param, Style, StyleError, Vertex, brightness, increasing
from .registry import register


@register
class Cel(Style):
    name = "cel"
    summary = "GI cel shading: brightness quantized to levels, colour kept (S5.2)"
    params = (
        Param("thresholds", "floats", None, "brightness steps between levels, increasing",
              auto="the scene's first-hit brightness quantiles 1/(K+1)..K/(K+1) for K+1 levels (equal bands; unresolved: evenly spaced k/(K+1))"),
        Param("levels", "floats", (0.4, 0.95), "target brightness of each band (one more than thresholds)", low=0.0),
    )
    default_inner = 16

    def validate(self) -> None:
        t, m = self.thresholds, self.levels
        if t is None:
            return
        if any(b <= a for a, b in zip(t, t[1:])):
            raise StyleError(f"bad value {','.join(map(str, t))!r} for parameter 'thresholds': must increase")
        if len(m) != len(t) + 1:
            raise StyleError(f"bad value {','.join(map(str, m))!r} for parameter 'levels': "
                             f"expected {len(t) + 1} levels for {len(t)} thresholds")

    def steps(self) -> tuple[float, ...]:
        """The thresholds in use: the given or resolved ones, else evenly spaced k/(K+1)."""
        if self.thresholds is not None:
            return self.thresholds
        k = len(self.levels)
        return tuple(i / k for i in range(1, k))

    def auto_values(self, facts) -> dict:
        if self.thresholds is not None:
            return {}
        k = len(self.levels)
        return {"thresholds": increasing(facts.brightness([i / k for i in range(1, k)]))}

    def target(self, u: mi.Float) -> mi.Float:
        out = mi.Float(self.levels[0])
        for t, m in zip(self.steps(), self.levels[1:]):
            out = dr.select(u >= t, m, out)
        return out

    def step_thresholds(self, v: Vertex) -> tuple:
        return self.steps()

    def curvature(self, I: mi.Color3f, v: Vertex, h: mi.Float) -> mi.Color3f:
        # constant along grey inside a band (I * level / u of a grey shift keeps the band's level); its
        # jumps are the thresholds
        return mi.Color3f(0.0)

    def apply(self, I: mi.Color3f, v: Vertex) -> mi.Color3f:
        u = brightness(I)
        target = self.target(u)
        return dr.select(u > 0, I * (target / dr.maximum(u, 1e-30)), mi.Color3f(target))
