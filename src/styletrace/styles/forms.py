"""Forms of a style function that the unbiased estimators can take (main paper Sec. 4, Theorem 4.1).

A style whose g is affine, a power series or a polynomial fit returns one of these from `form()`;
`styletrace.config.estimator_registry` turns it into the estimator the user picked. Styles with
discontinuities (cel, colour maps, hatching, ...) have no form: only direct application applies.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Optional, Sequence


@dataclass(frozen=True)
class AffineForm:
    """g(I) = a1 I + a0; a1 a scalar, per-channel vector or 3x3 matrix, a0 a scalar or per-channel
    vector."""

    a1: Any
    a0: Any = 0.0


@dataclass(frozen=True)
class SeriesForm:
    """g(I) = scale * h(gain I + shift) + offset with h a power series (`estimators.Series`).

    `gain` is a style's exposure: every sample is scaled by it before the series sees it (an
    exposure is linear in the expectation, gain E[X] = E[gain X], so the estimators stay unbiased,
    and the expansion point, its floor `pilot_lo` and the series keep their meaning in exposed units
    on a scene of any brightness). `shift` moves the samples into the series' convergence region
    (e.g. 1/(1+I) is the reciprocal series of 1 + I). The expansion point is b = max(pilot_scale *
    mean of the pilot children, pilot_lo): `pilot_lo` keeps b away from 0 (a power series of I^p
    about b converges only for 0 < I < 2b, so a pilot of zeros would make it diverge), and
    `pilot_scale` > 1 widens that region beyond a pilot that underestimates I. `values` is the range
    (lo, hi) g takes on radiance >= 0 (hi None: unbounded), if known: an unbiased estimate outside
    it is measured noise (`styletrace.wild`).
    """

    series: Any
    shift: float = 0.0
    gain: float = 1.0
    scale: Any = 1.0
    offset: Any = 0.0
    pilot_lo: Optional[float] = None
    pilot_scale: float = 1.0
    values: Optional[tuple] = None


@dataclass(frozen=True)
class PolynomialForm:
    """g(I) ~ fit(clamp(gain I, lo, hi)): a fitted polynomial (`estimators.Fit`), samples scaled by
    `gain` (a style's exposure) and clamped to the fit's domain first (the clamp is part of the
    style, as in the paper's tie-dye setup)."""

    fit: Any
    lo: float
    hi: float
    gain: float = 1.0


@dataclass(frozen=True)
class CompositeForm:
    """g = g_k o ... o g_1 with every operand's form known (`forms`, in application order). The
    `combined` estimator nests their estimators; where every operand is affine, `affine` is the
    composite AffineForm (and the `affine` estimator applies too)."""

    forms: tuple
    affine: Optional[AffineForm] = None


Form = Any
__all__: Sequence[str] = ["AffineForm", "SeriesForm", "PolynomialForm", "CompositeForm", "Form"]
