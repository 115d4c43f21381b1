"""cel: global-illumination cel shading (supplement S5.2).

Parameters
- bands (int, default 3, in [2, 8]): the number of bands K+1 where neither list is given
- thresholds (floats, default auto): increasing steps t_1 < ... < t_K; auto: the brightness
  quantiles 1/(K+1), ..., K/(K+1) of the first hits (unresolved: k/(K+1))
- levels (floats, default auto): K+1 target brightnesses m_0..m_K; auto: `tone.band_levels`

With u = (r+g+b)/3 of <I> and j the number of thresholds t_i <= u:
    g(<I>) = <I> m_j / u   (grey (m_j, m_j, m_j) if u <= 0)
Auto rules: docs/design/scene_relative_defaults.md.
"""
from __future__ import annotations

from styletrace.gate import dr, mi
from styletrace.styles.base import Param, Style, StyleError, Vertex, brightness, increasing, rounded
from styletrace.styles.registry import register_style
from styletrace.styles.tone import band_levels, luminance_of

#: the lightness range of the levels of an unresolved cel (evenly spaced over the bands)
FALLBACK_LSTAR = (30.0, 85.0)


@register_style
class Cel(Style):
    name = "cel"
    summary = "GI cel shading: brightness quantized to levels, colour kept (S5.2)"
    params = (
        Param(
            "bands",
            "int",
            3,
            "number of bands where neither thresholds nor levels is given",
            low=2,
            high=8,
        ),
        Param(
            "thresholds",
            "floats",
            None,
            "brightness steps between levels, increasing",
            auto="the scene's first-hit brightness quantiles 1/(K+1)..K/(K+1) for K+1 levels "
                 "(equal bands; unresolved: evenly spaced k/(K+1))",
        ),
        Param(
            "levels",
            "floats",
            None,
            "target brightness of each band (one more than thresholds)",
            low=0.0,
            auto="each band's median brightness with the scene's median at middle grey, >= 18 L* "
                 "apart (unresolved: evenly spaced in lightness)",
        ),
    )
    default_inner = 16

    def validate(self) -> None:
        t, m = self.thresholds, self.levels
        if t is not None and any(b <= a for a, b in zip(t, t[1:])):
            raise StyleError(f"bad value {','.join(map(str, t))!r} for parameter 'thresholds': "
                             "must increase")
        if t is not None and m is not None and len(m) != len(t) + 1:
            raise StyleError(f"bad value {','.join(map(str, m))!r} for parameter 'levels': "
                             f"expected {len(t) + 1} levels for {len(t)} thresholds")

    @property
    def band_count(self) -> int:
        """K+1: from the levels or thresholds given, else `bands`."""
        if self.levels is not None:
            return len(self.levels)
        if self.thresholds is not None:
            return len(self.thresholds) + 1
        return self.bands

    def steps(self) -> tuple[float, ...]:
        """The thresholds in use: the given or resolved ones, else evenly spaced k/(K+1)."""
        if self.thresholds is not None:
            return self.thresholds
        k = self.band_count
        return tuple(i / k for i in range(1, k))

    def band_values(self) -> tuple[float, ...]:
        """The levels in use: the given or resolved ones, else evenly spaced in lightness."""
        if self.levels is not None:
            return self.levels
        k = self.band_count
        lo, hi = FALLBACK_LSTAR
        return tuple(rounded(float(luminance_of(lo + (hi - lo) * j / (k - 1)))) for j in range(k))

    def auto_values(self, facts) -> dict:
        k = self.band_count
        out = {}
        if self.thresholds is None:
            out["thresholds"] = increasing(facts.brightness([i / k for i in range(1, k)]))
        if self.levels is None:
            out["levels"] = increasing(band_levels(facts.brightness, k))
        return out

    def target(self, u: mi.Float) -> mi.Float:
        """m_j, the level of u's band (j the number of thresholds <= u).

        Args:
            u: brightness per lane (mi.Float).

        Returns:
            mi.Float.
        """
        levels = self.band_values()
        out = mi.Float(levels[0])
        for t, m in zip(self.steps(), levels[1:]):
            out = dr.select(u >= t, m, out)
        return out

    def step_thresholds(self, v: Vertex) -> tuple:
        return self.steps()

    def curvature(self, I: mi.Color3f, v: Vertex, h: mi.Float) -> mi.Color3f:
        # constant along grey inside a band (I * level / u of a grey shift keeps the band's
        # level); its jumps are the thresholds
        return mi.Color3f(0.0)

    def apply(self, I: mi.Color3f, v: Vertex) -> mi.Color3f:
        u = brightness(I)
        target = self.target(u)
        return dr.select(u > 0, I * (target / dr.maximum(u, 1e-30)), mi.Color3f(target))
