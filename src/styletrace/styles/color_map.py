"""color_map: brightness mapped through a colour gradient (supplement S5.1).

Parameters
- gradient (gradient, default preset 'dusk'): stops 'pos:colour;...' over brightness

With u = (r+g+b)/3 of the inner estimate <I>:
    g(<I>) = G(clamp(u, u_first, u_last))
where G interpolates the gradient's stops linearly.
"""
from __future__ import annotations

import mitsuba as mi

from .base import Param, Style, Vertex, brightness
from .gradient import Gradient
from .registry import register


@register
class ColorMap(Style):
    name = "color_map"
    summary = "brightness mapped to a colour gradient, clamped to its ends (S5.1)"
    params = (Param("gradient", "gradient", Gradient.parse("dusk"), "colour stops over brightness"),)
    default_inner = 16

    def apply(self, I: mi.Color3f, v: Vertex) -> mi.Color3f:
        return self.gradient.eval(brightness(I))
