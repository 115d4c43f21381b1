"""reinhard: the reciprocal tone curve I / (1 + I), per channel (a style with a reciprocal-series form).

Parameters
- white (float, default 1.0): 0 < w <= 1000, the radiance mapped to 1/2

    g(<I>) = <I> / (w + <I>) = 1 - w / (w + <I>)            per channel.

Unbiased estimators use the reciprocal series of the shifted samples w + X (supplement S16-S17):
w/(w + I) = sum_k w b^(-k-1) (b - (w + I))^k about a pilot estimate b of w + I, which converges for
0 < w + I < 2b; b = max(1.5 <w + I>_pilot, w) leaves a margin above a pilot that underestimates. Samples of
w + X are >= w > 0, so the expansion never straddles 0.
"""
from __future__ import annotations

import mitsuba as mi

from .base import Param, Style, Vertex
from .forms import SeriesForm
from .registry import register

#: Largest w: the unbiased estimators expand in float32 samples w + X, which resolve X only to w 2^-24
#: (6e-5 at w = 1e3); at w = 3e5 the series estimator returned NaN (measured on the Cornell box).
MAX_WHITE = 1e3


@register
class Reinhard(Style):
    name = "reinhard"
    summary = "reciprocal tone curve I/(w + I), per channel (reciprocal series, S16-S17)"
    params = (Param("white", "float", 1.0, "radiance mapped to 1/2", low=0.0, low_open=True, high=MAX_WHITE),)
    default_inner = 16

    def apply(self, I: mi.Color3f, v: Vertex) -> mi.Color3f:
        return I / (self.white + I)

    def form(self):
        from ..estimators import reciprocal_series
        # samples of w + X are >= w, so a pilot b >= w keeps the expansion on the positive side
        return SeriesForm(reciprocal_series(self.white), shift=self.white, scale=-1.0, offset=1.0, pilot_lo=self.white,
                          pilot_scale=1.5, values=(0.0, 1.0))
