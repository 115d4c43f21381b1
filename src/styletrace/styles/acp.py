"""acp: the per-sample colour mapping baseline the paper compares against (supplement S5.1, Fig. 7).

Reference: "Global Illumination-Aware Stylised Shading", Kohei Doi, Yuki Morimoto, Reiji Tsuruno
(2021).

Parameters
- gradient (gradient, default preset 'dusk'): stops 'pos:colour;...' over (rescaled) brightness, clamped at the ends
- range (floats lo,hi, default auto): the brightness mapped onto the gradient's first and last stop, as
  `color_map`'s (auto: the 5% and 95% quantiles of the scene's first-hit brightness; unresolved: the first
  and last stop, i.e. brightness taken absolutely)

Applied to each single path sample L (not to an estimate of the expectation), with Y = (r+g+b)/3 of L and
u_0, u_last the first and last stop positions:
    Y' = u_0 + (Y - lo) (u_last - u_0) / (hi - lo),      g(L) = max(Y', 0.01) G(clamp(Y', u_0, u_last))
and the pixel is the average of g over the samples. Y' is the position `color_map` maps the same brightness
to, so with the same range the two use the same colours and differ only where the baseline is meant to
differ: g of each sample rather than of their mean, and the shading factor max(Y', 0.01) (in gradient units,
so that it, too, is the same on a dim and a bright scene). With range = the first and last stop, Y' = Y and
this is Doi et al.'s g(L) = max(Y, 0.01) G(clamp(Y)).
`per_sample = True` tells the integrator to apply g to every child sample and average, instead of applying
g to the mean of the children. Because g is nonlinear, E[g(L)] differs from g(E[L]): this is biased with
respect to the stylized rendering equation by design, and is there only as the baseline the paper's colour
mapping (`color_map`) is compared with. `default_inner` matches `color_map`, so equal-cost comparisons need no
extra settings.
"""
from __future__ import annotations

from ..gate import dr, mi
from .base import Vertex, brightness
from .color_map import ColorMap
from .registry import register


@register
class ACP(ColorMap):
    """The colour map's parameters, range rule and checks (`ColorMap`), applied per path sample."""
    name = "acp"
    summary = "baseline (Doi et al. 2021): max(Y', 0.01) colormap(Y') per path sample, Y' rescaled as color_map's; biased by design"
    default_inner = 16
    per_sample = True

    def apply(self, I: mi.Color3f, v: Vertex) -> mi.Color3f:
        lo, hi = self.span()
        u0, u1 = self.gradient.stops[0][0], self.gradient.stops[-1][0]
        Y = u0 + (brightness(I) - lo) * ((u1 - u0) / (hi - lo))
        return self.gradient.eval(Y) * dr.maximum(Y, 0.01)
