"""tie_dye: per-channel cosine waves (supplement S5.5, the polynomial-approximation example).

Parameters
- frequencies (floats, default 2,2.15,2.3): f_r, f_g, f_b > 0, in units of pi (one value: all)
- phases (floats, default 1,1.13,1.29): phi_r, phi_g, phi_b (one value: all channels)
- domain_min (float, default -1), domain_max (float, default 4): the fit interval [lo, hi], lo <
  hi, with pi max(f) (max(|lo|, |hi|) + max|phi|) <= 2^14
- exposure (float in (0, 100], default auto): s, the scale of <I>; auto: 0.18 / the median
  first-hit brightness (at most 100; unresolved: 1)

Per channel c:  g_c(x_c) = (1 - cos(pi f_c (clamp(s x_c, lo, hi) + phi_c))) / 2. Where the clamp
applies: docs/design/tie_dye_clamp.md.
"""
from __future__ import annotations

import math
from typing import Callable

from styletrace.gate import dr, mi
from styletrace.styles.base import Param, Style, StyleError, Vertex, auto_exposure, exposure_param
from styletrace.styles.forms import PolynomialForm
from styletrace.styles.registry import register_style

#: Degree of the Chebyshev fit the unbiased estimators use (supplement S5.5).
FIT_DEGREE = 20
#: Largest cosine argument pi f (x + phi) the kernel is handed: float32 (24-bit mantissa) resolves
#: an argument below 2^14 to 2^-10 ~ 0.001 rad, a colour error below 8-bit quantisation; larger
#: arguments lose the radiance x in rounding, and huge ones make cos return NaN.
MAX_ARGUMENT = float(2 ** 14)


@register_style
class TieDye(Style):
    name = "tie_dye"
    summary = "per-channel cosine waves (1 - cos(pi f (x + phi)))/2 (S5.5)"
    params = (
        Param(
            "frequencies",
            "floats",
            (2.0, 2.15, 2.3),
            "angular frequency per channel, in units of pi",
            low=0.0,
            low_open=True,
        ),
        Param("phases", "floats", (1.0, 1.13, 1.29), "phase offset per channel"),
        Param("domain_min", "float", -1.0, "lower end of the clamp / fit interval"),
        Param("domain_max", "float", 4.0, "upper end of the clamp / fit interval"),
        exposure_param(),
    )
    default_inner = 16

    @property
    def scale(self) -> float:
        return 1.0 if self.exposure is None else self.exposure

    def auto_values(self, facts) -> dict:
        return {} if self.exposure is not None else {"exposure": auto_exposure(facts)}

    def validate(self) -> None:
        for key in ("frequencies", "phases"):
            vals = self.values[key]
            if len(vals) == 1:
                self.values[key] = vals * 3
            elif len(vals) != 3:
                raise StyleError(
                    f"bad value {','.join(f'{x:g}' for x in vals)!r} for parameter '{key}': "
                    f"expected 1 or 3 numbers (r,g,b)"
                )
        if not self.domain_min < self.domain_max:
            raise StyleError(
                f"bad value {self.domain_max:g} for parameter 'domain_max': must exceed "
                f"domain_min = {self.domain_min:g}"
            )
        largest = math.pi * max(self.frequencies) * (max(-self.domain_min, self.domain_max)
                                                     + max(map(abs, self.phases)))
        if largest > MAX_ARGUMENT:
            raise StyleError(
                f"bad values frequencies={','.join(f'{x:g}' for x in self.frequencies)}, "
                f"phases={','.join(f'{x:g}' for x in self.phases)}, domain [{self.domain_min:g}, "
                f"{self.domain_max:g}]: the cosine's argument pi f (x + phi) reaches "
                f"{largest:.3g}; it must stay below {MAX_ARGUMENT:g} for float32 to resolve it"
            )

    def domain(self) -> tuple[float, float]:
        return (self.domain_min, self.domain_max)

    def form(self):
        from styletrace.estimators import chebyshev_fit
        lo, hi = self.domain()
        # the paper's Fig. 11 setup: a degree-20 Chebyshev fit per channel on the clamp interval
        # fitted in exposed units on [lo, hi]; the estimators expose each sample (gain) before the
        # clamp
        return PolynomialForm(chebyshev_fit(list(self.channel_functions()), FIT_DEGREE, lo, hi),
                              lo, hi, gain=self.scale)

    def channel_functions(self) -> tuple[Callable, Callable, Callable]:
        """g_r, g_g, g_b of the exposed value y = s x as numpy callables (array in, array out),
        clamp to the domain included (the fit's functions: the estimators expose the samples
        themselves)."""
        import numpy as np
        lo, hi = self.domain()

        def make(f: float, phi: float) -> Callable:
            def g(x):
                return (1.0 - np.cos(math.pi * f * (np.clip(x, lo, hi) + phi))) * 0.5
            return g

        return tuple(make(f, phi) for f, phi in zip(self.frequencies, self.phases))

    def apply(self, I: mi.Color3f, v: Vertex) -> mi.Color3f:
        x = dr.clip(I * self.scale, self.domain_min, self.domain_max)
        f = mi.Color3f(*(math.pi * f for f in self.frequencies))
        phi = mi.Color3f(*self.phases)
        return (1.0 - dr.cos(f * (x + phi))) * 0.5
