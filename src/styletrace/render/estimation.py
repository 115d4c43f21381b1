"""Glue between a style and the estimator that turns child samples into g(E[L]).

The `estimator` property of the `stylized` integrator (and of `styled` BSDFs) names one of ESTIMATORS.
`direct` works for every style; the unbiased ones need the style's `form()` (see `styles.forms`):

| name             | form       | what it is (styletrace.estimators)                         | inner_samples n means |
|------------------|------------|-------------------------------------------------------------|-----------------------|
| direct           | any        | g(mean of n children), biased O(1/n) (Eq. 19)               | children per estimate |
| affine           | affine     | a1 <I>_n + a0 (S1-S3)                                       | children per estimate |
| series           | series     | iterative prefix sum, Poisson-CMF truncation, U-statistic terms (S12) | pilot samples for b |
| series_recursive | series     | recursive prefix sum / Russian roulette, cumulative truncation, naive terms (S13) | pilot samples for b |
| series_single    | series     | single term, Poisson truncation (S11)                       | pilot samples for b   |
| ustat            | polynomial | U-statistic of the fitted polynomial about a pilot b (S7-S8, Eq. 17) | children (>= degree) |
| naive            | polynomial | products of independent children per term (S6)              | pilot samples for b   |
| telescoping      | any form   | debiased direct application (Eq. 15)                        | n0, the first level   |

Series and telescoping estimators draw a random number of children per lane; the draws happen inside
the lane's own loop, so lanes are never widened. `make_estimator` returns an object with
    run(draw, carry, uniform, active, like=mi.Color3f) -> (value, carry)
"""
from __future__ import annotations

import drjit as dr
import mitsuba as mi

from .. import estimators as E
from ..styles import StyleError
from ..styles.base import Style
from ..styles.forms import AffineForm, PolynomialForm, SeriesForm

#: Highest series term the renderer evaluates. Products of (x - b) over radiance samples with fireflies
#: (a light hit at 18x the pixel's mean) overflow float32 past ~30 terms; the estimate is unbiased for the
#: series truncated here, whose remainder is below (|I - b| / b)^24 (< 1e-7 for |I - b| < b/2).
SERIES_MAX_TERMS = 24

ESTIMATORS = {
    "direct": None,
    "affine": AffineForm,
    "series": SeriesForm,
    "series_recursive": SeriesForm,
    "series_single": SeriesForm,
    "ustat": PolynomialForm,
    "naive": PolynomialForm,
    "telescoping": object,  # any style with a form (a smooth g)
}
FORM_NAMES = {AffineForm: "affine", SeriesForm: "power-series", PolynomialForm: "polynomial"}


def applicable(style: Style) -> list[str]:
    """Estimator names that apply to `style`."""
    form = style.form()
    out = []
    for name, need in ESTIMATORS.items():
        if need is None or (form is not None and (need is object or isinstance(form, need))):
            out.append(name)
    return out


def check_estimator(name: str, style: Style) -> None:
    if name not in ESTIMATORS:
        raise StyleError(f"unknown estimator '{name}': available are {', '.join(ESTIMATORS)}")
    ok = applicable(style)
    if name not in ok:
        form = style.form()
        what = FORM_NAMES.get(type(form), "no unbiased") + " form"
        raise StyleError(f"estimator '{name}' does not apply to style '{style.name}' (it has {what}): "
                         f"use one of {', '.join(ok)}")


class Transformed:
    """An estimator of h(X') with X' = f(X) per sample and the result mapped by scale * value + offset."""

    def __init__(self, inner, sample=None, scale=1.0, offset=0.0):
        self.inner, self.sample, self.scale, self.offset = inner, sample, scale, offset
        self.name, self.mean_samples = inner.name, getattr(inner, "mean_samples", None)

    def run(self, draw, carry, uniform, active, like):
        if self.sample is not None:
            base = draw

            def draw(c):  # noqa: F811 (wraps the caller's draw)
                x, c = base(c)
                return self.sample(x), c
        value, carry = self.inner.run(draw, carry, uniform, active, like=like)
        if self.scale != 1.0 or self.offset != 0.0:
            value = value * self.scale + self.offset
        return value, carry


def make_estimator(slot, level: int, vertex):
    """The estimator `slot.estimator` for the slot's style at stylized level `level` (trace time)."""
    style, name, n = slot.style, slot.estimator, slot.n(level)
    form = style.form()

    if name == "direct":
        if style.per_sample:  # the children arrive already styled (a baseline): just average them
            return Transformed(E.Mean(n))
        return Transformed(E.Direct(lambda I: style.apply(I, vertex), n))
    if name == "telescoping":
        return Transformed(E.Telescoping(lambda I: style.apply(I, vertex), n0=n))
    if isinstance(form, AffineForm):
        return Transformed(E.Affine(form.a1, form.a0, n=n))
    if isinstance(form, SeriesForm):
        selection = {"series": "iterative", "series_recursive": "recursive", "series_single": "single"}[name]
        est = E.SeriesEstimator(form.series, b=E.Pilot(n, lo=form.pilot_lo, scale=form.pilot_scale),
                                selection=selection, max_terms=SERIES_MAX_TERMS)
        shift = form.shift
        return Transformed(est, (lambda x: x + shift) if shift else None, form.scale, form.offset)
    if isinstance(form, PolynomialForm):
        lo, hi = form.lo, form.hi
        if name == "ustat":
            est = E.PolynomialU(form.fit, n=max(n, form.fit.degree), b=E.Pilot(1))
        else:
            est = E.PolynomialNaive(form.fit, b=E.Pilot(n))
        return Transformed(est, lambda x: dr.clip(x, lo, hi))
    raise AssertionError(f"estimator {name} for form {form!r}")
