"""The estimator registry: how the `stylized` integrator turns n child samples into g(E[L]).

Each entry names the forms of g it accepts (`styles.forms`), what `inner_samples` n means for it,
its fixed parameters and a doc line; `styletrace styles` and the docs print this table, the settings
check names against it, and `make_estimator` builds the kernel object from it. It mirrors the style
registry.

    est = make_estimator(slot, level, vertex)
    value, carry = est.run(draw, carry, uniform, active, like=mi.Color3f)

Series and telescoping estimators draw a random number of children per lane; the draws happen inside
the lane's own loop, so lanes are never widened.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Callable

from styletrace import estimators as E
from styletrace.errors import SettingsError
from styletrace.gate import dr
from styletrace.styles.base import Style
from styletrace.styles.forms import AffineForm, CompositeForm, PolynomialForm, SeriesForm

#: Highest series term the renderer evaluates. Products of (x - b) over radiance samples with
#: fireflies (a light hit at 18x the pixel's mean) overflow float32 past ~30 terms; the estimate is
#: unbiased for the series truncated here, whose remainder is below (|I - b| / b)^24 (< 1e-7 for
#: |I - b| < b/2).
SERIES_MAX_TERMS = 24

#: The series with the expansion pass (settings.expansion_pass): b* from the pass changes how the
#: terms decay (rho^k with rho = cv^2 / (1 + cv^2), close to 1 on firefly pixels), so the truncation
#: keeps 8 terms always and continues with probability 0.9 up to 64 terms, evaluated scaled
#: (SeriesEstimator(scaled=True)), whose factors stay within float32 (measured:
#: benchmarks/gamma_series.py; docs/estimators.md).
PASS_TRUNCATION = (0.9, 8)
PASS_MAX_TERMS = 64
#: b = PASS_B_SCALE x b*: children up to 2 x PASS_B_SCALE x b* stay inside |x - b| < b, where the
#: series converges; the pass's b* is low wherever its m children missed a rare bright one, and a
#: child far beyond 2b enters every term's products. Measured (32x32, equal time,
#: benchmarks/gamma_series.py's scenes): scale 1 gave glossy-sphere images with MSE 1e6 (values to
#: -5e5), 2 gave 0.008-0.016, 4 gave 0.03 and 128.
PASS_B_SCALE = 2.0

#: forms whose presence makes an estimator applicable; ANY_FORM: any style that has a form (a
#: smooth g)
ANY_FORM = (AffineForm, SeriesForm, PolynomialForm, CompositeForm)
#: the estimators whose estimate needs only the mean of the children: a buffer of means replays
#: them (`lookdev.restyle`), and the expectation denoiser styles D with them
MEAN_ESTIMATORS = ("direct", "affine")
FORM_NAMES = {AffineForm: "affine", SeriesForm: "power-series", PolynomialForm: "polynomial",
              CompositeForm: "composite"}


@dataclass(frozen=True)
class EstimatorKind:
    """One registry entry; `forms` None means every style (no form needed)."""

    name: str
    forms: tuple[type, ...] | None
    doc: str
    inner: str                                   # what inner_samples n means for it
    params: dict[str, str] = field(default_factory=dict)  # fixed internals, for the docs
    build: Callable | None = None                # (style, n, vertex) -> Transformed
    when: Callable | None = None                 # a further condition on the form, if any

    def accepts(self, style: Style) -> bool:
        """Whether this estimator applies to a style.

        Args:
            style: the style, whose `form()` is tested against `forms` and `when`.

        Returns:
            True where `forms` is None, or the style's form is one of them and passes `when`.
        """
        if self.forms is None:
            return True
        form = style.form()
        return isinstance(form, self.forms) and (self.when is None or self.when(form))

    def describe_forms(self) -> str:
        if self.forms is None:
            return "any"
        if self.forms == ANY_FORM:
            return "any form"
        if self.forms == (AffineForm, CompositeForm):
            return "affine (or a composition of affine styles)"
        return ", ".join(FORM_NAMES[f] for f in self.forms)


_REGISTRY: dict[str, EstimatorKind] = {}


def estimator(name: str, forms, doc: str, inner: str, when=None, **params: str):
    """Register the decorated builder `(style, n, vertex) -> Transformed` under `name`.

    Args:
        name: the registry name (a later registration of the name replaces the earlier).
        forms: the form classes it accepts (`styles.forms`), or None for every style.
        doc, inner: the docs' line, and what inner_samples n means for it.
        when: a further condition on the style's form, or None.
        **params: fixed internals, name -> text, for the docs.

    Returns:
        The decorator, which registers the builder and returns it unchanged.
    """
    def deco(build):
        _REGISTRY[name] = EstimatorKind(name, forms, doc, inner, dict(params), build, when)
        return build
    return deco


def estimator_names() -> list[str]:
    return list(_REGISTRY)


def estimator_entry(name: str) -> EstimatorKind:
    """The registry entry of an estimator.

    Args:
        name: the estimator's registry name.

    Returns:
        Its `EstimatorKind`.

    Raises:
        SettingsError: no estimator of that name (the message lists those available).
    """
    try:
        return _REGISTRY[name]
    except KeyError:
        raise SettingsError(f"unknown estimator '{name}': available are "
                            f"{', '.join(_REGISTRY)}") from None


def kinds() -> list[EstimatorKind]:
    return list(_REGISTRY.values())


def applicable(style: Style) -> list[str]:
    """Estimator names that apply to `style`.

    Args:
        style: the style to test (`EstimatorKind.accepts`).

    Returns:
        The names, in registration order.
    """
    return [k.name for k in _REGISTRY.values() if k.accepts(style)]


def check_estimator(name: str, style: Style) -> str:
    """`name` if it is an estimator that applies to `style`.

    Args:
        name: an estimator's registry name.
        style: the style it is to estimate.

    Returns:
        `name`.

    Raises:
        SettingsError: an unknown estimator, or one that does not apply (naming those that do).
    """
    if not estimator_entry(name).accepts(style):
        form = style.form()
        what = FORM_NAMES.get(type(form), "no unbiased") + " form"
        if isinstance(form, CompositeForm) and form.affine is not None:
            what = "an affine composite form"
        raise SettingsError(
            f"estimator '{name}' does not apply to style '{style.name}' (it has {what}): "
            f"use one of {', '.join(applicable(style))}"
        )
    return name


class Transformed:
    """An estimator of h(X') with X' = f(X) per sample and the result mapped by scale * value +
    offset; `name` and `mean_draws` are the inner estimator's.

    Args:
        inner: the estimator of h (`estimators.Estimator` or a composite with the same `run`).
        sample: f, applied to each sample `draw` returns; None: the identity.
        scale, offset: the map of the inner estimate (floats, or per-channel arrays).
    """

    def __init__(self, inner, sample=None, scale=1.0, offset=0.0):
        self.inner, self.sample, self.scale, self.offset = inner, sample, scale, offset
        self.name, self.mean_draws = inner.name, getattr(inner, "mean_draws", None)

    def run(self, draw, carry, uniform, active, like):
        """One estimate per lane, as `estimators.Estimator.run` (the kernel contract).

        Args:
            draw: draw(carry[, u]) -> (x, carry), one sample X per lane (f is applied here).
            carry: the caller's opaque pytree, handed through draw and uniform.
            uniform: uniform(carry) -> (u, carry), one uniform per lane.
            active: the lanes that take part (mi.Bool or a numpy bool array), or None for all.
            like: the type of x (e.g. mi.Color3f; required for Dr.Jit).

        Returns:
            (value, carry): scale * the inner estimate + offset (0 on inactive lanes), and carry.
        """
        if self.sample is not None:
            base = draw

            def draw(c):  # noqa: F811 (wraps the caller's draw)
                x, c = base(c)
                return self.sample(x), c
        value, carry = self.inner.run(draw, carry, uniform, active, like=like)
        if self.scale != 1.0 or self.offset != 0.0:
            value = value * self.scale + self.offset
        return value, carry


def check_adaptive(name: str, style: Style, raw) -> None:
    """Adaptive inner counts (`n0:n_max`) only with direct application of a function of expectation:
    the unbiased estimators' guarantee does not survive a data-dependent number of children
    (docs/adaptive.md).

    Args:
        name: the slot's estimator name; style: its style.
        raw: the `inner_samples` value as given, for the message.

    Raises:
        SettingsError: an estimator other than direct, or a per-sample style.
    """
    if name != "direct":
        raise SettingsError(
            f"bad value {raw!r} for 'inner_samples' with estimator '{name}': adaptive counts "
            f"n0:n_max stop on the data, which makes the unbiased estimators biased; use estimator "
            f"direct or a fixed count"
        )
    if style.per_sample:
        raise SettingsError(
            f"bad value {raw!r} for 'inner_samples' with style '{style.name}': it averages "
            f"g over its children (not g of their mean), which adaptive stopping would bias; use a "
            f"fixed count"
        )


def adaptive_direct(style, n0: int, n_max: int, vertex, z: float, bias: float):
    """Direct application with adaptive stopping (`estimators.AdaptiveDirect`), told by the style
    where its steps are (`Style.step_thresholds`) and how curved it is (`Style.curvature`).

    Args:
        style: the style g; vertex: the `styles.base.Vertex` it is applied at.
        n0, n_max: the children drawn first, and the most drawn (n0 <= n_max).
        z: the confidence band in standard errors (`adaptive_z`).
        bias: the predicted-bias target of smooth styles (`adaptive_bias`).

    Returns:
        The `estimators.AdaptiveDirect` (not wrapped in `Transformed`).
    """
    return E.AdaptiveDirect(
        lambda I: style.apply(I, vertex),
        n0,
        n_max,
        thresholds=style.step_thresholds(vertex),
        curvature=lambda I, h: style.curvature(I, vertex, h),
        z=z,
        bias=bias,
    )


def make_estimator(slot, level: int, vertex, settings=None, moments=None,
                   emitted=None) -> Transformed:
    """The estimator `slot.estimator` for the slot's style at stylized level `level` (trace time).

    Args:
        slot: the `settings.StyleSlot`; level: the stylized level (0: the first), picks n.
        vertex: the `styles.base.Vertex` the style is applied at.
        settings: the parsed `Settings` or None. With direct application, an adaptive count or
            error AOVs give `AdaptiveDirect` (its `stats` feed the AOVs); `firefly` caps children.
        moments: (sets, known) of `series_with_pass`, from the expansion pass; used by "series" at
            level 0 only. emitted: the vertex's own emission, left out of the firefly cap.

    Returns:
        The estimator; without any of these, the registry's builder's.
    """
    if moments is not None and level == 0 and slot.estimator == "series":
        return series_with_pass(slot.style, *moments)
    n = slot.n(level)
    n_max = getattr(n, "n_max", None)
    aovs = settings is not None and settings.aovs and level == 0
    if (n_max is not None or aovs) and slot.estimator == "direct" and not slot.style.per_sample:
        z, bias = ((settings.adaptive_z, settings.adaptive_bias) if settings is not None
                   else (2.0, 2e-3))
        return Transformed(adaptive_direct(slot.style, int(n), n_max or int(n), vertex, z, bias))
    cap = firefly_cap(settings)
    style = slot.style
    if slot.estimator == "direct":
        # the values pinned from the scene are kernel inputs: an edit that moves them (a moved
        # object changes the pilot's quantiles) reuses the compiled megakernel; given values stay
        # literals, so a render of given values draws what it drew before
        style = style.opaque(style.chosen)
    if cap is not None and slot.estimator == "direct" and not style.per_sample:
        return _capped(lambda I: style.apply(I, vertex), int(n), cap, emitted)
    return estimator_entry(slot.estimator).build(style, int(n), vertex)


def _capped(g, n: int, cap: tuple[float, float], emitted) -> Transformed:
    """Direct application of g with the firefly cap on the children's reflected part (each child
    less the vertex's own emission `emitted`, added back before g; None: the children as they
    are)."""
    if emitted is None:
        return Transformed(E.Direct(g, n, cap=cap))
    return Transformed(E.Direct(lambda I: g(I + emitted), n, cap=cap),
                       sample=lambda x: x - emitted)


def firefly_cap(settings) -> tuple[float, float] | None:
    """(k, floor) of the firefly control for direct application (`estimators.affine.MeanOfN`), or
    None where it is off (firefly 0, no settings, or error AOVs, which describe the paper's
    estimator). An unresolved floor (no pilot ran) is 0.

    Args:
        settings: the parsed `Settings` (its `firefly`, `firefly_floor`, `aovs`), or None.

    Returns:
        (k, floor) as floats, or None.
    """
    k = getattr(settings, "firefly", 0.0) if settings is not None else 0.0
    if not k or settings.aovs:
        return None
    return float(k), float(settings.firefly_floor or 0.0)


def child_mean(slot, level: int, settings=None, emitted=None) -> Transformed:
    """The mean of a slot's n children as direct application computes it (the firefly control
    included): what an expectation buffer keeps and restyles from (`lookdev.record`).

    Args:
        slot: the `settings.StyleSlot`; level: the stylized level, which picks n.
        settings: the parsed `Settings` (for `firefly_cap`), or None: no cap.
        emitted: the vertex's own emission, left out of the cap; None: the children as they are.

    Returns:
        The estimator of the mean (capped only for direct application of a non-per-sample style).
    """
    cap = (firefly_cap(settings) if slot.estimator == "direct" and not slot.style.per_sample
           else None)
    if cap is None:
        return Transformed(E.Direct(lambda x: x, slot.n(level)))
    return _capped(lambda x: x, slot.n(level), cap, emitted)


# ---- the registry ------------------------------------------------------------------------------

@estimator("direct", None,
           "g(mean of n children), biased O(1/n) (Eq. 19); with n0:n_max adaptive, n chosen per "
           "vertex (estimators/adaptive.py)", "children per estimate (or n0:n_max)")
def _direct(style, n, vertex):
    if style.per_sample:  # the children arrive already styled (a baseline): just average them
        return Transformed(E.Mean(n))
    return Transformed(E.Direct(lambda I: style.apply(I, vertex), n))


def _affine_form(form):
    """The AffineForm of a style: its own, or an all-affine composition's."""
    return form.affine if isinstance(form, CompositeForm) else form


@estimator("affine", (AffineForm, CompositeForm), "a1 <I>_n + a0, unbiased (S1-S3)",
           "children per estimate", when=lambda form: _affine_form(form) is not None)
def _affine(style, n, vertex):
    form = _affine_form(style.form())
    return Transformed(E.Affine(form.a1, form.a0, n=n))


def _series_sample(form):
    """The per-sample map gain x + shift of a SeriesForm (None where it is the identity)."""
    gain, shift = form.gain, form.shift
    if gain == 1.0:
        return (lambda x: x + shift) if shift else None
    return lambda x: x * gain + shift


def _clamp_sample(form):
    """The per-sample map clamp(gain x, lo, hi) of a PolynomialForm."""
    gain, lo, hi = form.gain, form.lo, form.hi
    return (lambda x: dr.clip(x, lo, hi)) if gain == 1.0 else (lambda x: dr.clip(x * gain, lo, hi))


def _series(selection):
    def build(style, n, vertex):
        form = style.form()
        est = E.SeriesEstimator(form.series, b=E.Pilot(n, lo=form.pilot_lo, scale=form.pilot_scale),
                                selection=selection, max_terms=SERIES_MAX_TERMS)
        return Transformed(est, _series_sample(form), form.scale, form.offset)
    return build


def series_with_pass(style, sets, known=0.0) -> Transformed:
    """The series estimator expanded about PASS_B_SCALE x b*, b* = E[X'^2] / E[X'] of the sample
    X' = gain X + shift = gain known + shift + gain R, the largest over `sets`. No pilot children;
    b floored at the form's pilot_lo and clamped into the series' convergence region as a pilot's.

    Args:
        style: a style with a `SeriesForm`.
        sets: (mean r, mean r^2) pairs of the expansion pass (per lane: its pixel's, its window's).
        known: the lane's own part of every child, R = X - known (its vertex's emission).

    Returns:
        The `SeriesEstimator` (iterative, geometric truncation PASS_TRUNCATION), transformed.
    """
    form = style.form()
    gain = form.gain
    e = known * gain + form.shift
    b = None
    for m1, m2 in sets:
        m1, m2 = m1 * gain, m2 * (gain * gain)  # the moments of gain R
        m1, m2 = e + m1, e * e + (2.0 * e) * m1 + m2
        bs = dr.select(m1 > 0.0, m2 / dr.select(m1 > 0.0, m1, 1.0), 0.0)
        b = bs if b is None else dr.maximum(b, bs)
    b = b * PASS_B_SCALE
    # scaled terms for series whose b is kept > 0 (powers, reciprocals); exp's coefficients never
    # overflow
    scaled = isinstance(form.series, (E.PowerFunctionSeries, E.ReciprocalSeries))
    est = E.SeriesEstimator(
        form.series,
        b=E.PerLane(b, lo=form.pilot_lo),
        selection="iterative",
        truncation=E.Geometric(*PASS_TRUNCATION),
        max_terms=PASS_MAX_TERMS,
        scaled=scaled,
    )
    return Transformed(est, _series_sample(form), form.scale, form.offset)


_PILOT = "pilot samples for the expansion point b"
estimator(
    "series",
    (SeriesForm,),
    "power series, iterative prefix sum, Poisson-CMF truncation, U-statistic terms (S12)",
    _PILOT,
    max_terms=str(SERIES_MAX_TERMS),
)(_series("iterative"))
estimator(
    "series_recursive",
    (SeriesForm,),
    "power series, recursive prefix sum (Russian roulette), "
    "cumulative truncation, naive terms (S13)",
    _PILOT,
    max_terms=str(SERIES_MAX_TERMS),
)(_series("recursive"))
estimator(
    "series_single",
    (SeriesForm,),
    "power series, single term, Poisson truncation (S11)",
    _PILOT,
    max_terms=str(SERIES_MAX_TERMS),
)(_series("single"))


@estimator("ustat", (PolynomialForm,),
           "U-statistic of the fitted polynomial about a pilot b (S7-S8, Eq. 17)",
           "children (at least the fit's degree)", pilot="1 sample")
def _ustat(style, n, vertex):
    form = style.form()
    est = E.PolynomialU(form.fit, n=max(n, form.fit.degree), b=E.Pilot(1))
    return Transformed(est, _clamp_sample(form))


@estimator("naive", (PolynomialForm,),
           "products of independent children per polynomial term (S6)", _PILOT)
def _naive(style, n, vertex):
    form = style.form()
    return Transformed(E.PolynomialNaive(form.fit, b=E.Pilot(n)), _clamp_sample(form))


@estimator("telescoping", ANY_FORM, "debiased direct application (Eq. 15)", "n0, the first level",
           truncation="power law 1.5")
def _telescoping(style, n, vertex):
    return Transformed(E.Telescoping(lambda I: style.apply(I, vertex), n0=n))


def _operand(form, n: int):
    """An estimator that consumes samples of an operand's input and returns an unbiased estimate
    of the operand applied to their mean, as the single-style builders above do (sample maps
    become 1-sample inner estimators: a gain and shift is Affine(gain, shift), a clamp is
    Direct(clip, 1))."""
    if isinstance(form, AffineForm):
        return E.Affine(form.a1, form.a0, n=1)
    if isinstance(form, SeriesForm):
        est = E.SeriesEstimator(form.series,
                                b=E.Pilot(n, lo=form.pilot_lo, scale=form.pilot_scale),
                                selection="iterative", max_terms=SERIES_MAX_TERMS)
        if form.shift or form.gain != 1.0:
            est = E.Compose(est, E.Affine(form.gain, form.shift, n=1))
        if form.scale != 1.0 or form.offset != 0.0:
            est = E.Compose(E.Affine(form.scale, form.offset, n=1), est)
        return est
    if isinstance(form, PolynomialForm):
        return E.Compose(E.PolynomialNaive(form.fit, b=E.Pilot(n)),
                         E.Direct(_clamp_sample(form), 1))
    raise AssertionError(f"no operand estimator for {form!r}")


@estimator("combined", (CompositeForm,),
           "a composition's operands' unbiased estimators nested (Theorem 4.1): each outer operand "
           "consumes independent estimates of the inner ones",
           "pilot samples of series and polynomial operands (affine operands take 1)")
def _combined(style, n, vertex):
    forms = style.form().forms
    est = _operand(forms[0], n)
    for form in forms[1:]:
        est = E.Compose(_operand(form, n), est)
    return Transformed(est)


__all__ = [
    "EstimatorKind",
    "MEAN_ESTIMATORS",
    "estimator",
    "estimator_names",
    "estimator_entry",
    "kinds",
    "applicable",
    "check_estimator",
    "check_adaptive",
    "adaptive_direct",
    "make_estimator",
    "firefly_cap",
    "child_mean",
    "Transformed",
    "SERIES_MAX_TERMS",
    "series_with_pass",
    "PASS_TRUNCATION",
    "PASS_MAX_TERMS",
    "PASS_B_SCALE",
]
