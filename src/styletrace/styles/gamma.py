"""gamma: per-channel gamma correction of the expected radiance (main paper Eq. 24).

Parameters
- gamma (float, default 2.2): gamma > 0

    g(<I>) = max(<I>, 0)^(1/gamma)        per channel.

Negative inputs (possible with unbiased inner estimates) are clamped to 0 before the power.
"""
from __future__ import annotations

import drjit as dr
import mitsuba as mi

from .base import Param, Style, Vertex
from .registry import register


@register
class Gamma(Style):
    name = "gamma"
    summary = "per-channel gamma I^(1/gamma) (Eq. 24)"
    params = (Param("gamma", "float", 2.2, "gamma exponent", low=0.0, low_open=True),)
    default_inner = 16

    def apply(self, I: mi.Color3f, v: Vertex) -> mi.Color3f:
        return dr.power(dr.maximum(I, 0.0), 1.0 / self.gamma)
