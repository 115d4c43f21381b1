"""contrast: affine contrast about a pivot (supplement S5.4).

Parameters
- c (float, default 1.5): contrast factor, >= 0
- pivot (float, default 0.5): brightness left unchanged

    g(<I>) = c (<I> - p) + p        per channel; affine, so every unbiased estimator of <I> suffices.
"""
from __future__ import annotations

import mitsuba as mi

from .base import Param, Style, Vertex
from .forms import AffineForm
from .registry import register


@register
class Contrast(Style):
    name = "contrast"
    summary = "affine contrast c(I - p) + p about a pivot p (S5.4)"
    params = (
        Param("c", "float", 1.5, "contrast factor", low=0.0),
        Param("pivot", "float", 0.5, "pivot brightness p"),
    )
    default_inner = 1

    def apply(self, I: mi.Color3f, v: Vertex) -> mi.Color3f:
        return (I - self.pivot) * self.c + self.pivot

    def form(self):
        return AffineForm(self.c, (1.0 - self.c) * self.pivot)
