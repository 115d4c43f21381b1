"""styletrace.estimators: estimators of g(E[X]) for stylized rendering as a function of expectation.

Reference: West and Mukherjee, "Stylized Rendering as a Function of Expectation" (2024). Pure
math, array-generic (numpy or Dr.Jit), no Mitsuba. Guide: docs/estimators.md.

Kernel contract (`base.Estimator.run`):
    value, carry = estimator.run(draw, carry, uniform, active=None, *, like=None)
draw(carry[, u]) -> (x, carry) gives one unbiased sample of I per lane, uniform(carry) -> (u,
carry) one uniform per lane; carry is an opaque pytree, active the lanes that take part, like the
type of x (required for Dr.Jit). Every estimator has `name`, `mean_draws`, `fixed_draws` and
`exact(I)`. Rationale: docs/design/estimator_kernel_contract.md.
"""
from __future__ import annotations

from styletrace.estimators.adaptive import AdaptiveDirect
from styletrace.estimators.affine import Affine, Mean, apply_linear
from styletrace.estimators.algebra import Compose, Product, Sum, inner_mean
from styletrace.estimators.arrays import channel_mean
from styletrace.estimators.base import Context, Estimator
from styletrace.estimators.coefficients import (
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
from styletrace.estimators.direct import Direct
from styletrace.estimators.fits import (
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
from styletrace.estimators.harness import (
    Distribution,
    Exponential,
    NumpyEstimate,
    TwoPoint,
    Uniform,
    channel_means,
    estimate_drjit,
    estimate_numpy,
)
from styletrace.estimators.pilot import PerLane, Pilot
from styletrace.estimators.polynomial import (
    PolynomialNaive,
    PolynomialU,
    u_statistic_means,
    ustat_update,
)
from styletrace.estimators.series import SeriesEstimator
from styletrace.estimators.telescoping import Telescoping
from styletrace.estimators.tie_dye_chebyshev import (
    TIE_DYE,
    tie_dye,
    tie_dye_b,
    tie_dye_fit,
    tie_dye_g,
    tie_dye_r,
)
from styletrace.estimators.truncation import (
    Cumulative,
    Geometric,
    Poisson,
    PoissonCMF,
    PowerLaw,
    Truncation,
    resolve_truncation,
)

__all__ = [
    "Estimator",
    "Context",
    "Direct",
    "AdaptiveDirect",
    "channel_mean",
    "Affine",
    "Mean",
    "apply_linear",
    "PolynomialNaive",
    "PolynomialU",
    "u_statistic_means",
    "ustat_update",
    "SeriesEstimator",
    "Telescoping",
    "Sum",
    "Product",
    "Compose",
    "inner_mean",
    "Pilot",
    "PerLane",
    "Truncation",
    "Cumulative",
    "PoissonCMF",
    "Poisson",
    "Geometric",
    "PowerLaw",
    "resolve_truncation",
    "Series",
    "PolynomialSeries",
    "ExpSeries",
    "ReciprocalSeries",
    "PowerFunctionSeries",
    "TaylorSeries",
    "exp_series",
    "reciprocal_series",
    "power_series",
    "gamma_series",
    "taylor_series",
    "polynomial_series",
    "taylor_shift",
    "Fit",
    "chebyshev_fit",
    "legendre_fit",
    "bernstein_fit",
    "taylor_fit",
    "to_unit",
    "from_unit",
    "chebyshev_nodes",
    "even_nodes",
    "gauss_legendre",
    "chebyshev_basis",
    "legendre_basis",
    "TIE_DYE",
    "tie_dye",
    "tie_dye_r",
    "tie_dye_g",
    "tie_dye_b",
    "tie_dye_fit",
    "estimate_numpy",
    "estimate_drjit",
    "channel_means",
    "NumpyEstimate",
    "Distribution",
    "Uniform",
    "Exponential",
    "TwoPoint",
]
