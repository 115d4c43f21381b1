"""reinhard: the reciprocal tone curve I / (1 + I), per channel (a reciprocal-series form).

Parameters
- white (float, default 1.0): 0 < w <= 1000, the exposed radiance mapped to 1/2
- exposure (float in (0, 100], default auto): s, the scale of <I>; auto: 0.18 / the median
  first-hit brightness (`scene.defaults`), at most 100; unresolved: 1

    g(<I>) = s <I> / (w + s <I>) = 1 - w / (w + s <I>)            per channel.

Unbiased estimators use the reciprocal series of w + s X about b = max(1.5 <w + s X>_pilot, w)
(supplement S16-S17; docs/design/power_series.md).
"""
from __future__ import annotations

from styletrace.gate import mi
from styletrace.styles.base import Param, Style, Vertex, auto_exposure, exposure_param
from styletrace.styles.forms import SeriesForm
from styletrace.styles.registry import register_style

#: Largest w: the unbiased estimators expand in float32 samples w + X, which resolve X only to w
#: 2^-24 (6e-5 at w = 1e3); at w = 3e5 the series estimator returned NaN (measured on the Cornell
#: box).
MAX_WHITE = 1e3


@register_style
class Reinhard(Style):
    name = "reinhard"
    summary = "reciprocal tone curve I/(w + I), per channel (reciprocal series, S16-S17)"
    params = (
        Param(
            "white",
            "float",
            1.0,
            "exposed radiance mapped to 1/2",
            low=0.0,
            low_open=True,
            high=MAX_WHITE,
        ),
        exposure_param(),
    )
    default_inner = 16

    @property
    def scale(self) -> float:
        return 1.0 if self.exposure is None else self.exposure

    def auto_values(self, facts) -> dict:
        return {} if self.exposure is not None else {"exposure": auto_exposure(facts)}

    def apply(self, I: mi.Color3f, v: Vertex) -> mi.Color3f:
        x = I * self.scale
        return x / (self.white + x)

    def form(self):
        from styletrace.estimators import reciprocal_series
        # samples of w + s X are >= w, so a pilot b >= w keeps the expansion on the positive side
        return SeriesForm(
            reciprocal_series(self.white),
            gain=self.scale,
            shift=self.white,
            scale=-1.0,
            offset=1.0,
            pilot_lo=self.white,
            pilot_scale=1.5,
            values=(0.0, 1.0),
        )
