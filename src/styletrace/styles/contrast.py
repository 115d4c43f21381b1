"""contrast: affine contrast about a pivot (supplement S5.4).

Parameters
- c (float, default 1.5): contrast factor, >= 0
- pivot (float, default 0.5): brightness left unchanged
- exposure (float in (0, 100], default auto): s, the scale of <I>; auto: 0.5 / the median
  first-hit brightness (at most 100), whatever the pivot; unresolved: 1

    g(<I>) = c (s <I> - p) + p        per channel.

Affine, so every unbiased estimator of <I> suffices. Why the auto exposure ignores the pivot:
docs/design/scene_relative_defaults.md.
"""
from __future__ import annotations

from styletrace.gate import mi
from styletrace.styles.base import Param, Style, Vertex, auto_exposure, exposure_param
from styletrace.styles.forms import AffineForm
from styletrace.styles.registry import register_style

#: where the auto exposure puts the scene's median brightness: the default pivot
MID = 0.5


@register_style
class Contrast(Style):
    name = "contrast"
    summary = "affine contrast c(s I - p) + p about a pivot p, exposure s (S5.4)"
    params = (
        Param("c", "float", 1.5, "contrast factor", low=0.0),
        Param("pivot", "float", 0.5, "pivot brightness p"),
        exposure_param(
            f"{MID:g} / the median of the scene's first-hit brightness, at most 100 (unresolved: 1)"
        ),
    )
    default_inner = 1

    @property
    def scale(self) -> float:
        return 1.0 if self.exposure is None else self.exposure

    def auto_values(self, facts) -> dict:
        # contrast spreads tones about the pivot: the scene's median goes to the default pivot
        # (middle grey, 0.18, would leave most of the image below 0 after c = 1.5 about 0.5)
        return {} if self.exposure is not None else {"exposure": auto_exposure(facts, MID)}

    def apply(self, I: mi.Color3f, v: Vertex) -> mi.Color3f:
        return (I * self.scale - self.pivot) * self.c + self.pivot

    def form(self):
        # c (s I - p) + p = (c s) I + (1 - c) p: the exposure is part of the linear coefficient
        return AffineForm(self.c * self.scale, (1.0 - self.c) * self.pivot)
