"""The tie-dye style of the paper's Fig. 11 and its degree-20 Chebyshev fit (supplement S5.5).

    r' = (1 - cos(2 pi (r + 1))) / 2
    g' = (1 - cos(2.15 pi (g + 1.13))) / 2
    b' = (1 - cos(2.3 pi (b + 1.29))) / 2

`tie_dye_fit` fits each channel on [-1, 4]; clamping samples above 4 is the caller's (a bias).
Measured errors: docs/estimators.md; rationale: docs/design/tie_dye_clamp.md.
"""
from __future__ import annotations

import math

from styletrace.estimators import arrays as A
from styletrace.estimators.fits import Fit, chebyshev_fit

__all__ = ["tie_dye_r", "tie_dye_g", "tie_dye_b", "TIE_DYE", "tie_dye", "tie_dye_fit"]


def tie_dye_r(r):
    """The red channel: (1 - cos(2 pi (r + 1))) / 2.

    Args:
        r: red values, numpy or Dr.Jit.

    Returns:
        r', in [0, 1], of r's kind.
    """
    return (1.0 - A.cos((2.0 * math.pi) * (r + 1.0))) * 0.5


def tie_dye_g(g):
    """The green channel: (1 - cos(2.15 pi (g + 1.13))) / 2.

    Args:
        g: green values, numpy or Dr.Jit.

    Returns:
        g', in [0, 1], of g's kind.
    """
    return (1.0 - A.cos((2.15 * math.pi) * (g + 1.13))) * 0.5


def tie_dye_b(b):
    """The blue channel: (1 - cos(2.3 pi (b + 1.29))) / 2.

    Args:
        b: blue values, numpy or Dr.Jit.

    Returns:
        b', in [0, 1], of b's kind.
    """
    return (1.0 - A.cos((2.3 * math.pi) * (b + 1.29))) * 0.5


TIE_DYE = (tie_dye_r, tie_dye_g, tie_dye_b)


def tie_dye(x):
    """All three channels of a value.

    Args:
        x: numpy (..., 3) or a 3-channel Dr.Jit array (e.g. mi.Color3f).

    Returns:
        (r', g', b'), of x's kind and shape.
    """
    if A.is_drjit(x):
        return type(x)(tie_dye_r(x[0]), tie_dye_g(x[1]), tie_dye_b(x[2]))
    import numpy as np
    x = np.asarray(x)
    return np.stack([tie_dye_r(x[..., 0]), tie_dye_g(x[..., 1]), tie_dye_b(x[..., 2])], axis=-1)


def tie_dye_fit(degree: int = 20, lo: float = -1.0, hi: float = 4.0,
                nodes: str = "chebyshev") -> Fit:
    """The per-channel Chebyshev fit of the tie-dye style (`fits.chebyshev_fit`).

    Args:
        degree: the fit's degree; lo, hi: the fit interval (above hi, the caller clamps).
        nodes: "chebyshev" or "even".

    Returns:
        A per-channel Fit, coefficients (degree + 1, 3).
    """
    return chebyshev_fit(list(TIE_DYE), degree, lo, hi, nodes=nodes)
