"""exp_tone: exponential tone curve, per channel (an analytic style with a power-series form).

Parameters
- exposure (float, default 1.5): 0 < k <= 87 (e^-k stays a normal float32)

    g(<I>) = 1 - exp(-k <I>) = 1 - a^<I>,  a = e^-k          per channel.

Unbiased estimators use the exponential series a^I = sum_k ln(a)^k a^b (I - b)^k / k! about a pilot
estimate b (supplement S14-S15); it converges for every I, so any pilot b is admissible.
"""
from __future__ import annotations

import math

import drjit as dr
import mitsuba as mi

from .base import Param, Style, Vertex
from .forms import SeriesForm
from .registry import register

#: Largest exposure k: e^-k must be a normal float32 (k < -ln(1.18e-38) = 87.3).
MAX_EXPOSURE = 87.0


@register
class ExpTone(Style):
    name = "exp_tone"
    summary = "exponential tone curve 1 - exp(-k I), per channel (series form, S14-S15)"
    # k <= 87 < -ln(FLT_MIN) = 87.3: the series' base a = e^-k, and exp(-k I) at unit radiance, stay normal
    # float32 numbers (above 1.2e-38) instead of flushing to 0, where ln(a) and the series break down
    params = (Param("exposure", "float", 1.5, "exposure k", low=0.0, low_open=True, high=MAX_EXPOSURE),)
    default_inner = 16

    def apply(self, I: mi.Color3f, v: Vertex) -> mi.Color3f:
        return 1.0 - dr.exp(-self.exposure * I)

    def form(self):
        from ..estimators import exp_series
        return SeriesForm(exp_series(math.exp(-self.exposure)), scale=-1.0, offset=1.0, values=(0.0, 1.0))
