"""Glue between a style and the estimator that turns child samples into g(E[L]).

`make_estimator(slot, level, vertex)` returns an object with
    run(draw, carry, uniform, active) -> (value, carry)
where `draw(carry)` traces one child sample (the carry holds the sampler), `uniform(carry)` draws a
uniform number for random truncation, and `active` masks the lanes to stylize.
"""
from __future__ import annotations

import drjit as dr
import mitsuba as mi

from ..styles import StyleError
from ..styles.base import Style


class DirectApplication:
    """Direct application g(<I>_n), <I>_n the mean of n child samples (main paper Eq. 19).

    Biased for nonlinear g with bias ~ tr(H_g Cov)/(2n) (Eq. 21), consistent as n grows.
    """

    name = "direct"

    def __init__(self, g, n: int):
        self.g, self.n = g, n
        self.mean_samples = n

    def run(self, draw, carry, uniform, active):
        n = self.n

        def cond(carry, i, total):
            return active & (i < n)

        def body(carry, i, total):
            x, carry = draw(carry)
            return carry, i + 1, total + x

        carry, _, total = dr.while_loop((carry, mi.UInt32(0), mi.Spectrum(0.0)), cond, body,
                                        labels=("carry", "i", "total"), label="styletrace inner samples")
        return self.g(total * (1.0 / n)), carry


ESTIMATORS = ("direct",)


def check_estimator(name: str, style: Style) -> None:
    if name not in ESTIMATORS:
        raise StyleError(f"unknown estimator '{name}' for style '{style.name}': available are "
                         f"{', '.join(ESTIMATORS)}")


def make_estimator(slot, level: int, vertex):
    style = slot.style
    return DirectApplication(lambda I: style.apply(I, vertex), slot.n(level))
