"""styletrace.estimators: estimators of g(E[X]) for stylized rendering as a function of expectation.

West & Mukherjee, "Stylized Rendering as a Function of Expectation" (SIGGRAPH 2024) applies a style
function g to the expectation I = E[X] of radiance. This package estimates g(I) from samples of X:
pure math, array-generic (numpy or Dr.Jit), no Mitsuba. Guide: docs/estimators.md.

Kernel contract (stable; what the integrator calls)
------------------------------------------------------
    value, carry = estimator.run(draw, carry, uniform, active=None, *, like=None)

    draw(carry) -> (x, carry)
        ONE new independent unbiased sample of I per lane and the updated carry. numpy: shape
        (lanes,) or (lanes, C); Dr.Jit: Float / Array3f / mitsuba.Color3f / any Dr.Jit array type.
        Called once per loop iteration, inside the loop body only, and only on lanes that still want a
        sample: lanes draw different counts when the truncation is random. If the estimator (or a part)
        uses a stratified comb (``uses_comb``), it is called as draw(carry, u) instead, u (a per-lane
        Float / (lanes,) array) being the first primary dimension the sample must use.
    uniform(carry) -> (u, carry)
        one uniform [0, 1) number per lane (numpy (lanes,), Dr.Jit Float) for random decisions.
    carry
        opaque pytree threaded through the loop state (Dr.Jit: e.g. a Mitsuba sampler; every variable
        the loop changes, carry included, is loop state, so no iteration reuses random numbers).
        numpy: tuple/list/dict whose per-lane leaves have the lane count as first axis (the numpy loop
        compacts active lanes, so draw/uniform must size their output from the carry).
    active
        lanes that take part; other lanes draw nothing and return 0.
    like
        the type (or an instance) of x. Required for Dr.Jit (e.g. like=mitsuba.Color3f), because the
        loop state must be typed before the first draw; optional for numpy (gives lanes/dtype).
    value
        like x: same type (Dr.Jit) or same shape and dtype (numpy).

    Every estimator also has ``name``, ``mean_samples`` (expected draw() calls per estimate, or None
    where it depends on the data, i.e. adaptive "cumulative" truncation), ``fixed_samples`` and
    ``exact(I)`` (the function its expectation equals; for Direct, the target g).

Public API
----------
    Direct(g, n, comb=False)                       g(<I>_n), biased O(1/n)
    AdaptiveDirect(g, n0, n_max, thresholds=(), curvature=None, z=2, bias=1e-3)
                                                   g(<I>_n) with n in [n0, n_max] chosen per lane (adaptive.py)
    Affine(a1, a0=0, n=1, comb=False), Mean(m, comb=False)
    PolynomialNaive(poly, b=None)                  products of k samples per term (S6)
    PolynomialU(poly, n, b=None)                   U-statistic, Kettunen et al. 2021 recurrence (S7-S8)
    SeriesEstimator(series, b=Pilot(1), selection="iterative", truncation=None, terms=None, max_terms=64,
                    scaled=False)
    Telescoping(g, n0=1, truncation=PowerLaw(1.5), max_terms=2**16)
    Sum(*parts, shared=True), Product(*factors), Compose(outer, inner), inner_mean(est, m, comb=False)
    Pilot(n=1, lo=None, hi=None)                   expansion point from separate pilot samples
    PerLane(b, lo=None)                            expansion point per lane, given (a separate pass's)
    truncations: Cumulative, PoissonCMF, Poisson, Geometric, PowerLaw
    series: exp_series, reciprocal_series, power_series, gamma_series, taylor_series, polynomial_series
    fits: chebyshev_fit, legendre_fit, bernstein_fit, taylor_fit, Fit (.to_monomial(b), .series(b))
    tie-dye: tie_dye_r, tie_dye_g, tie_dye_b, tie_dye, tie_dye_fit(degree=20, lo=-1, hi=4)
    harness: estimate_numpy, estimate_drjit, channel_means, Uniform, Exponential, TwoPoint
"""
from __future__ import annotations

from .adaptive import AdaptiveDirect
from .affine import Affine, Mean, apply_linear
from .algebra import Compose, Product, Sum, inner_mean
from .arrays import channel_mean
from .base import Context, Estimator
from .coefficients import (
                           ExpSeries,
                           PolynomialSeries,
                           PowerFunctionSeries,
                           ReciprocalSeries,
                           Series,
                           TaylorSeries,
                           exp_series,
                           gamma_series,
                           polynomial_series,
                           power_series,
                           reciprocal_series,
                           taylor_series,
                           taylor_shift,
)
from .direct import Direct
from .fits import (
                           Fit,
                           bernstein_fit,
                           chebyshev_basis,
                           chebyshev_fit,
                           chebyshev_nodes,
                           even_nodes,
                           from_unit,
                           gauss_legendre,
                           legendre_basis,
                           legendre_fit,
                           taylor_fit,
                           to_unit,
)
from .harness import (
                           Distribution,
                           Exponential,
                           NumpyEstimate,
                           TwoPoint,
                           Uniform,
                           channel_means,
                           estimate_drjit,
                           estimate_numpy,
)
from .pilot import PerLane, Pilot
from .polynomial import PolynomialNaive, PolynomialU, u_statistic_means, ustat_update
from .series import SeriesEstimator
from .telescoping import Telescoping
from .tie_dye_chebyshev import TIE_DYE, tie_dye, tie_dye_b, tie_dye_fit, tie_dye_g, tie_dye_r
from .truncation import (
                           Cumulative,
                           Geometric,
                           Poisson,
                           PoissonCMF,
                           PowerLaw,
                           Truncation,
                           resolve_truncation,
)

__all__ = [
    "Estimator", "Context", "Direct", "AdaptiveDirect", "channel_mean", "Affine", "Mean", "apply_linear", "PolynomialNaive", "PolynomialU",
    "u_statistic_means", "ustat_update", "SeriesEstimator", "Telescoping", "Sum", "Product", "Compose",
    "inner_mean", "Pilot", "PerLane", "Truncation", "Cumulative", "PoissonCMF", "Poisson", "Geometric", "PowerLaw",
    "resolve_truncation", "Series", "PolynomialSeries", "ExpSeries", "ReciprocalSeries", "PowerFunctionSeries",
    "TaylorSeries", "exp_series", "reciprocal_series", "power_series", "gamma_series", "taylor_series",
    "polynomial_series", "taylor_shift", "Fit", "chebyshev_fit", "legendre_fit", "bernstein_fit", "taylor_fit",
    "to_unit", "from_unit", "chebyshev_nodes", "even_nodes", "gauss_legendre", "chebyshev_basis",
    "legendre_basis", "TIE_DYE", "tie_dye", "tie_dye_r", "tie_dye_g", "tie_dye_b", "tie_dye_fit",
    "estimate_numpy", "estimate_drjit", "channel_means", "NumpyEstimate", "Distribution", "Uniform", "Exponential", "TwoPoint",
]
