"""acp: the per-sample colour mapping baseline the paper compares against (supplement S5.1, Fig. 7).

Reference: "Global Illumination-Aware Stylised Shading", Kohei Doi, Yuki Morimoto, Reiji Tsuruno
(2021).

Parameters
- gradient (gradient, default preset 'dusk'): stops 'pos:colour;...' over brightness, clamped at the ends

Applied to each single path sample L (not to an estimate of the expectation), with Y = (r+g+b)/3 of L:
    g(L) = max(Y, 0.01) G(clamp(Y, Y_first, Y_last))
and the pixel is the average of g over the samples. `per_sample = True` tells the integrator to apply
g to every child sample and average, instead of applying g to the mean of the children. Because g is
nonlinear, E[g(L)] differs from g(E[L]): this is biased with respect to the stylized rendering equation
by design, and is there only as the baseline the paper's colour mapping (`color_map`) is compared with.
`default_inner` matches `color_map`, so equal-cost comparisons need no extra settings.
"""
from __future__ import annotations

import drjit as dr
import mitsuba as mi

from .base import Param, Style, Vertex, brightness
from .gradient import Gradient
from .registry import register


@register
class ACP(Style):
    name = "acp"
    summary = "baseline (Doi et al. 2021): max(Y, 0.01) colormap(Y) per path sample, biased by design"
    params = (Param("gradient", "gradient", Gradient.parse("dusk"), "colour stops over brightness"),)
    default_inner = 16
    per_sample = True

    def apply(self, I: mi.Color3f, v: Vertex) -> mi.Color3f:
        Y = brightness(I)
        return self.gradient.eval(Y) * dr.maximum(Y, 0.01)
