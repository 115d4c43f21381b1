"""acp: the per-sample colour mapping baseline the paper compares against (supplement S5.1, Fig. 7).

Reference: Doi, Morimoto, Tsuruno, "Global Illumination-Aware Stylised Shading" (2021).

Parameters
- gradient (gradient, default preset 'dusk'): stops 'pos:colour;...' over brightness, clamped
- range (floats lo,hi, default auto): the brightness mapped onto the first and last stop (auto:
  the 5% and 95% first-hit brightness quantiles; unresolved: the first and last stop)

Per path sample L, Y = (r+g+b)/3 of L: Y' = u_0 + (Y - lo) (u_last - u_0) / (hi - lo),
g(L) = max(Y', 0.01) G(clamp(Y', u_0, u_last)), averaged over the samples (`per_sample = True`;
biased by design). Rationale: docs/design/acp_baseline.md.
"""
from __future__ import annotations

from styletrace.gate import dr, mi
from styletrace.styles.base import Vertex, brightness
from styletrace.styles.color_map import ColorMap
from styletrace.styles.registry import register_style


@register_style
class ACP(ColorMap):
    """The colour map's parameters, range rule and checks (`ColorMap`), applied per path sample."""
    name = "acp"
    summary = ("baseline (Doi et al. 2021): max(Y', 0.01) colormap(Y') per path sample, Y' "
               "rescaled as color_map's; biased by design")
    default_inner = 16
    per_sample = True

    def apply(self, I: mi.Color3f, v: Vertex) -> mi.Color3f:
        lo, hi = self.span()
        u0, u1 = self.gradient.stops[0][0], self.gradient.stops[-1][0]
        Y = u0 + (brightness(I) - lo) * ((u1 - u0) / (hi - lo))
        return self.gradient.eval(Y) * dr.maximum(Y, 0.01)
