"""exp_tone: exponential tone curve, per channel (an analytic style with a power-series form).

Parameters
- exposure (float, default auto): 0 < k <= 87; auto: 1.5 x 0.18 / the median first-hit
  brightness (at most 87); unresolved: 1.5

    g(<I>) = 1 - exp(-k <I>) = 1 - a^<I>,  a = e^-k          per channel.

Unbiased estimators use the exponential series of a^I about a pilot b (supplement S14-S15),
which converges for every I (docs/design/power_series.md).
"""
from __future__ import annotations

import math
from dataclasses import replace

from styletrace.gate import dr, mi
from styletrace.styles.base import EXPOSURE_KEY, Style, Vertex, auto_exposure, exposure_param
from styletrace.styles.forms import SeriesForm
from styletrace.styles.registry import register_style

#: Largest exposure k: e^-k must be a normal float32 (k < -ln(1.18e-38) = 87.3).
MAX_EXPOSURE = 87.0
#: k of the tone curve on radiance exposed to the key value (and the unresolved fallback)
K_AT_KEY = 1.5


@register_style
class ExpTone(Style):
    name = "exp_tone"
    summary = "exponential tone curve 1 - exp(-k I), per channel (series form, S14-S15)"
    # k <= 87 < -ln(FLT_MIN) = 87.3: the series' base a = e^-k, and exp(-k I) at unit radiance, stay
    # normal float32 numbers (above 1.2e-38) instead of flushing to 0, where ln(a) and the series
    # break down
    params = (
        replace(
            exposure_param(),
            doc="exposure k",
            high=MAX_EXPOSURE,
            auto=f"{K_AT_KEY:g} x {EXPOSURE_KEY:g} / the median of the scene's first-hit "
                 f"brightness, at most {MAX_EXPOSURE:g} (unresolved: {K_AT_KEY:g})",
        ),
    )
    default_inner = 16

    @property
    def k(self) -> float:
        return K_AT_KEY if self.exposure is None else self.exposure

    def auto_values(self, facts) -> dict:
        return ({} if self.exposure is not None
                else {"exposure": auto_exposure(facts, K_AT_KEY * EXPOSURE_KEY, MAX_EXPOSURE)})

    def apply(self, I: mi.Color3f, v: Vertex) -> mi.Color3f:
        return 1.0 - dr.exp(-self.k * I)

    def form(self):
        from styletrace.estimators import exp_series
        return SeriesForm(exp_series(math.exp(-self.k)), scale=-1.0, offset=1.0, values=(0.0, 1.0))
