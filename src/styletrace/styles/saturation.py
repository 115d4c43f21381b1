"""saturation: blend towards grey or towards the maximally saturated colour (supplement S5.3).

Parameters
- w (float, default 0.5, in [0, 1]): weight of the grey (minimum-saturation) colour; w = 1 gives
  grey, w = 0 the maximally saturated colour, w = 0.5 the blend used for the paper's Fig. 9.

With u = (r+g+b)/3 of the inner estimate <I>, c_min / c_max its smallest / largest channel:
    I_min = (u, u, u)
    I_max = (<I> - c_min) / c_max                 (pre-normalised maximum saturation: min channel 0)
    u'    = (I_max,r + I_max,g + I_max,b) / 3
    g(<I>) = w I_min + (1 - w) I_max u / u'
The supplement prints the last factor as "u'/u'", which is 1 and would leave I_max un-normalised;
the text says "brightness normalized", so I_max is rescaled to brightness u, the reading used here.

Evaluation: c_max cancels in I_max u / u' = (<I> - c_min) u / s with s = brightness(<I> - c_min)
(= u' c_max), so it is computed in that form: no division by c_max, and well defined (each channel
of the saturated colour is at most 3u) whenever the channels are not all equal. For a grey input
(s = 0; this covers c_max = 0 and u' = 0) there is no hue to saturate and the result is I_min.
The style is meant for the "first N hits only" parametrization (recursive saturation).
"""
from __future__ import annotations

from ..gate import dr, mi
from .base import Param, Style, Vertex, brightness
from .registry import register


@register
class Saturation(Style):
    name = "saturation"
    summary = "blend of grey and maximally saturated colour at the same brightness (S5.3)"
    params = (Param("w", "float", 0.5, "weight of grey (1 = grey, 0 = maximally saturated)", low=0.0, high=1.0),)
    default_inner = 8

    def saturated(self, I: mi.Color3f) -> mi.Color3f:
        """The maximally saturated colour of brightness u = brightness(I) (I_min where I is grey)."""
        u = brightness(I)
        c_min = dr.minimum(dr.minimum(I.x, I.y), I.z)
        D = I - c_min                      # >= 0, smallest channel exactly 0
        s = brightness(D)                  # = u' c_max, computed from non-negative differences
        return dr.select(s > 0, D * (u / dr.select(s > 0, s, 1.0)), mi.Color3f(u))

    def apply(self, I: mi.Color3f, v: Vertex) -> mi.Color3f:
        u = brightness(I)
        return mi.Color3f(u) * self.w + self.saturated(I) * (1.0 - self.w)
