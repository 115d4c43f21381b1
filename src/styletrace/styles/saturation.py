"""saturation: blend towards grey or towards the maximally saturated colour (supplement S5.3).

Parameters
- w (float, default 0.5, in [0, 1]): weight of the grey colour; 1: grey, 0: the saturated colour

With u = (r+g+b)/3 of <I>, c_min / c_max its smallest / largest channel:
    I_min = (u, u, u),   I_max = (<I> - c_min) / c_max,   u' = brightness(I_max)
    g(<I>) = w I_min + (1 - w) I_max u / u'       (I_min for a grey input)
Meant for the "first N hits" parametrization (recursive saturation). Reading of the supplement:
docs/design/saturation_normalisation.md.
"""
from __future__ import annotations

from styletrace.gate import dr, mi
from styletrace.styles.base import Param, Style, Vertex, brightness
from styletrace.styles.registry import register_style


@register_style
class Saturation(Style):
    name = "saturation"
    summary = "blend of grey and maximally saturated colour at the same brightness (S5.3)"
    params = (Param("w", "float", 0.5, "weight of grey (1 = grey, 0 = "
                                       "maximally saturated)", low=0.0, high=1.0),)
    default_inner = 8

    def saturated(self, I: mi.Color3f) -> mi.Color3f:
        """The maximally saturated colour of brightness u = brightness(I) (I_min where I is
        grey).

        Args:
            I: the colour per lane (mi.Color3f).

        Returns:
            I_max u / u' (mi.Color3f).
        """
        u = brightness(I)
        c_min = dr.minimum(dr.minimum(I.x, I.y), I.z)
        D = I - c_min                      # >= 0, smallest channel exactly 0
        s = brightness(D)                  # = u' c_max, computed from non-negative differences
        return dr.select(s > 0, D * (u / dr.select(s > 0, s, 1.0)), mi.Color3f(u))

    def apply(self, I: mi.Color3f, v: Vertex) -> mi.Color3f:
        u = brightness(I)
        return mi.Color3f(u) * self.w + self.saturated(I) * (1.0 - self.w)
