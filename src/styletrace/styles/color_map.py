"""color_map: brightness mapped through a colour gradient (supplement S5.1).

Parameters
- gradient (gradient, default preset 'dusk'): stops 'pos:colour;...' over (rescaled) brightness
- range (floats lo,hi, default auto): the brightness mapped onto the gradient's first and last stop

With u = (r+g+b)/3 of <I>, u_0 and u_last the first and last stop positions:
    u' = u_0 + (u - lo) (u_last - u_0) / (hi - lo),      g(<I>) = G(clamp(u', u_0, u_last))
G interpolates the stops linearly. Auto range: the 5% and 95% brightness quantiles of what the
camera sees of the covered objects; unresolved: the first and last stop positions
(docs/design/scene_relative_defaults.md).
"""
from __future__ import annotations

from styletrace.gate import mi
from styletrace.styles.base import Param, Style, StyleError, Vertex, brightness, increasing
from styletrace.styles.gradient import Gradient
from styletrace.styles.registry import register_style


@register_style
class ColorMap(Style):
    name = "color_map"
    summary = "brightness mapped to a colour gradient, clamped to its ends (S5.1)"
    params = (
        Param("gradient", "gradient", Gradient.parse("dusk"), "colour stops over brightness"),
        Param(
            "range",
            "floats",
            None,
            "brightness lo,hi mapped onto the first and last stop",
            auto="the 5% and 95% quantiles of the scene's first-hit brightness (unresolved: the "
            "first and last stop)",
        ),
    )
    default_inner = 16

    def validate(self) -> None:
        r = self.range
        if r is not None and (len(r) != 2 or not r[1] > r[0]):
            raise StyleError(
                f"bad value {','.join(map(str, r))!r} for parameter 'range': expected two "
                f"increasing numbers lo,hi"
            )

    def span(self) -> tuple[float, float]:
        """(lo, hi) in use: the given or resolved range, else the gradient's own ends."""
        if self.range is not None:
            return self.range
        return self.gradient.stops[0][0], self.gradient.stops[-1][0]

    def auto_values(self, facts) -> dict:
        return ({} if self.range is not None
                else {"range": increasing(facts.brightness([0.05, 0.95]))})

    def apply(self, I: mi.Color3f, v: Vertex) -> mi.Color3f:
        lo, hi = self.span()
        u0, u1 = self.gradient.stops[0][0], self.gradient.stops[-1][0]
        return self.gradient.eval(u0 + (brightness(I) - lo) * ((u1 - u0) / (hi - lo)))
