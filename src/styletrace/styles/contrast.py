"""contrast: affine contrast about a pivot (supplement S5.4).

Parameters
- c (float >= 0, default auto): contrast factor; auto: the most contrast up to 1.5 that leaves the
  scene's 2% brightness quantile at or above black, min(1.5, 1 / (1 - q_02 / m)) >= 1 with m the
  median (unresolved, or the exposure given: 1.5)
- pivot (float, default auto): brightness left unchanged; auto: the scene's median exposed, v =
  min(0.5, 1 / (1 + c_auto (q_98 / m - 1))), the most (up to 0.5) that leaves the 98% quantile at
  or below white (unresolved, or the exposure given: 0.5)
- exposure (float in (0, 100], default auto): s, the scale of <I>; auto: v / m, so that the median
  is the pivot, at most 100 (unresolved: 1)

    g(<I>) = c (s <I> - p) + p        per channel.

Affine, so every unbiased estimator of <I> suffices. The auto values read the scene, never a given c
or pivot (`auto_values`), so a restyle or a fit with another c or pivot keeps the scene's exposure.
Why these rules: docs/design/tone_styles.md.
"""
from __future__ import annotations

from styletrace.gate import mi
from styletrace.styles.base import (
    MAX_EXPOSURE,
    Param,
    Style,
    Vertex,
    exposure_param,
    rounded,
)
from styletrace.styles.forms import AffineForm
from styletrace.styles.registry import register_style
from styletrace.styles.tone import HIGH_Q, LOW_Q

#: the largest auto contrast (the fixed default before issue 37) and its unresolved fallback
C_MAX = 1.5
#: the largest auto pivot, where the median is exposed to (the fixed default before issue 37) and
#: the unresolved fallback
MID = 0.5


@register_style
class Contrast(Style):
    name = "contrast"
    summary = "affine contrast c(s I - p) + p about a pivot p, exposure s (S5.4)"
    params = (
        Param("c", "float", None, "contrast factor", low=0.0,
              auto=f"min({C_MAX:g}, 1 / (1 - q_{LOW_Q:g} / m)): the most contrast up to "
                   f"{C_MAX:g} that keeps the scene's {LOW_Q:.0%} first-hit brightness quantile "
                   f"q_{LOW_Q:g} at or above black, m the median (unresolved, or the exposure "
                   f"given: {C_MAX:g})"),
        Param("pivot", "float", None, "pivot brightness p",
              auto=f"the median exposed, v = min({MID:g}, 1 / (1 + c (q_{HIGH_Q:g} / m - 1))) with "
                   f"the auto c: the most up to {MID:g} that keeps the {HIGH_Q:.0%} quantile at "
                   f"or below white (unresolved, or the exposure given: {MID:g})"),
        exposure_param(
            f"v / the median of the scene's first-hit brightness (the median at the auto pivot), "
            f"at most {MAX_EXPOSURE:g} (unresolved: 1)"
        ),
    )
    default_inner = 1

    @property
    def scale(self) -> float:
        return 1.0 if self.exposure is None else self.exposure

    @property
    def factor(self) -> float:
        """c as applied: the given or pinned value, else the unresolved C_MAX."""
        return C_MAX if self.c is None else self.c

    @property
    def fixed_point(self) -> float:
        """The pivot as applied: the given or pinned value, else the unresolved MID."""
        return MID if self.pivot is None else self.pivot

    def auto_values(self, facts) -> dict:
        # g(x) = c (x - v) + v with the median exposed to v: the 2% quantile stays >= 0 while
        # c <= 1 / (1 - q_lo / m) (>= 1, whatever v), and the 98% quantile <= 1 while
        # v <= 1 / (1 + c (q_hi / m - 1)). The rules use the auto c even where c is given, so
        # that a restyle or fit with another c or pivot keeps the exposure (lookdev.fit does not
        # fit it). A given exposure is no longer relative to the scene: c and pivot keep their
        # fallbacks, the defaults before issue 37. Measured: docs/design/tone_styles.md.
        if self.exposure is not None:
            return {}
        lo, median, hi = facts.brightness([LOW_Q, 0.5, HIGH_Q])
        if not median > 0:
            return {}  # a black scene: the unresolved fallbacks
        c = C_MAX if lo >= median else min(C_MAX, 1.0 / (1.0 - lo / median))
        v = min(MID, 1.0 / (1.0 + c * max(hi / median - 1.0, 0.0)))
        # the exposure first: the line of auto values names it as the other tone styles do
        chosen = {"exposure": rounded(min(v / median, MAX_EXPOSURE)), "c": rounded(c),
                  "pivot": rounded(v)}
        return {k: x for k, x in chosen.items() if self.values[k] is None}

    def apply(self, I: mi.Color3f, v: Vertex) -> mi.Color3f:
        return (I * self.scale - self.fixed_point) * self.factor + self.fixed_point

    def form(self):
        # c (s I - p) + p = (c s) I + (1 - c) p: the exposure is part of the linear coefficient
        return AffineForm(self.factor * self.scale, (1.0 - self.factor) * self.fixed_point)
