"""gamma: per-channel gamma correction of the expected radiance (main paper Eq. 24).

Parameters
- gamma (float, default 2.2): gamma >= 0.1 (smaller gammas overflow float32 on bright radiance)
- exposure (float in (0, 100], default auto): s, the scale of <I>; auto: 0.18 / the median
  first-hit brightness (`scene.defaults`), at most 100; unresolved: 1

    g(<I>) = max(s <I>, 0)^(1/gamma)        per channel (negative inputs clamp to 0).

Unbiased estimators use the binomial series of x^(1/gamma) of the exposed samples about
b = max(1.5 <x>_pilot, 0.02); it converges for 0 < I < 2b. Heavy tails, `expansion_pass` and the
wild-value warning: docs/design/power_series.md.
"""
from __future__ import annotations

import math

from styletrace.gate import dr, mi
from styletrace.styles.base import Param, Style, StyleError, Vertex, auto_exposure, exposure_param
from styletrace.styles.forms import SeriesForm
from styletrace.styles.registry import register_style

#: Expansion point of the unbiased estimators: b = max(PILOT_SCALE * pilot mean, PILOT_FLOOR)
#: (exposed radiance).
PILOT_FLOOR = 0.02
PILOT_SCALE = 1.5
#: Smallest gamma: the exponent 1/gamma <= 10 keeps I^(1/gamma) below float32's 3.4e38 for radiance
#: up to 7e3, beyond what a scene's lights reach, while as gamma -> 0 it overflows for any I > 1.
MIN_GAMMA = 0.1
#: The radiance MIN_GAMMA was chosen for: (s I)^(1/gamma) must stay below float32's largest number
#: for exposed radiance s I up to this, so an exposure and a small gamma that overflow together are
#: refused.
MAX_RADIANCE = 7e3
FLOAT32_MAX = 3.4028234663852886e38


@register_style
class Gamma(Style):
    name = "gamma"
    summary = "per-channel gamma I^(1/gamma) (Eq. 24)"
    params = (Param("gamma", "float", 2.2, "gamma exponent", low=MIN_GAMMA), exposure_param())
    default_inner = 16

    @property
    def scale(self) -> float:
        return 1.0 if self.exposure is None else self.exposure

    def validate(self) -> None:
        top = self.scale * MAX_RADIANCE
        if top > 1.0 and math.log(top) / self.gamma > math.log(FLOAT32_MAX):
            raise StyleError(
                f"bad values exposure={self.scale:g}, gamma={self.gamma:g}: (s I)^(1/gamma) "
                f"overflows float32 for radiance I up to {MAX_RADIANCE:g}; lower the exposure or "
                "raise gamma"
            )

    def auto_values(self, facts) -> dict:
        return {} if self.exposure is not None else {"exposure": auto_exposure(facts)}

    def apply(self, I: mi.Color3f, v: Vertex) -> mi.Color3f:
        return dr.power(dr.maximum(I * self.scale, 0.0), 1.0 / self.gamma)

    def form(self):
        from styletrace.estimators import gamma_series
        # binomial series of I^(1/gamma) about a pilot b > 0 (main paper Eq. 24); the floor and the
        # 1.5x margin keep dark or sparsely lit pixels inside the convergence region 0 < I < 2b
        # (measured in tests/styles/test_gamma.py and docs/estimators.md), on the exposed samples
        # s X (b and its floor in exposed units: the same on a scene of any brightness)
        return SeriesForm(
            gamma_series(self.gamma),
            gain=self.scale,
            pilot_lo=PILOT_FLOOR,
            pilot_scale=PILOT_SCALE,
            values=(0.0, None),
        )
