"""contrast: affine contrast about a pivot (supplement S5.4).

Parameters
- c (float, default 1.5): contrast factor, >= 0
- pivot (float, default 0.5): brightness left unchanged
- exposure (float in (0, 100], default auto): s, the scale of <I> before the contrast; auto: pivot / the median
  first-hit brightness of the scene (`plugins.scene_defaults`, at most 100), so the scene's middle tone sits at the pivot
  and a dim scene is not pushed below 0; unresolved (mi.render directly, or a pivot <= 0): 1

    g(<I>) = c (s <I> - p) + p        per channel; affine, so every unbiased estimator of <I> suffices.
"""
from __future__ import annotations

import mitsuba as mi

from .base import Param, Style, Vertex, auto_exposure, exposure_param
from .forms import AffineForm
from .registry import register


@register
class Contrast(Style):
    name = "contrast"
    summary = "affine contrast c(s I - p) + p about a pivot p, exposure s (S5.4)"
    params = (
        Param("c", "float", 1.5, "contrast factor", low=0.0),
        Param("pivot", "float", 0.5, "pivot brightness p"),
        exposure_param("the pivot / the median of the scene's first-hit brightness, at most 100 (unresolved, or a "
                       "pivot <= 0: 1)"),
    )
    default_inner = 1

    @property
    def scale(self) -> float:
        return 1.0 if self.exposure is None else self.exposure

    def auto_values(self, facts) -> dict:
        # contrast spreads tones about the pivot: the scene's median is put there (a pivot <= 0 gives no
        # admissible exposure, and the value is left unresolved)
        return {} if self.exposure is not None else {"exposure": auto_exposure(facts, self.pivot)}

    def apply(self, I: mi.Color3f, v: Vertex) -> mi.Color3f:
        return (I * self.scale - self.pivot) * self.c + self.pivot

    def form(self):
        # c (s I - p) + p = (c s) I + (1 - c) p: the exposure is part of the linear coefficient
        return AffineForm(self.c * self.scale, (1.0 - self.c) * self.pivot)
