"""sepia: colour map through a two-stop gradient extrapolated over [0, inf) (supplement S5.4).

Parameters
- gradient (gradient, default '0:#000000;1:#c4a27a'): exactly two stops (p0, c0), (p1, c1)

With u = (r+g+b)/3 of <I>, the segment extrapolated linearly instead of clamped:
    g(<I>) = c0 + (c1 - c0) (u - p0) / (p1 - p0)
Affine in <I>: `affine()` returns (A, b), A = (c1 - c0) (1/3, 1/3, 1/3)^T / (p1 - p0) and
b = c0 - (c1 - c0) p0 / (p1 - p0). More stops are refused (docs/design/estimator_algebra.md).
"""
from __future__ import annotations

from styletrace.gate import mi
from styletrace.styles.base import Param, Style, StyleError, Vertex, brightness
from styletrace.styles.forms import AffineForm
from styletrace.styles.gradient import Gradient
from styletrace.styles.registry import register_style

DEFAULT = "0:#000000;1:#c4a27a"


@register_style
class Sepia(Style):
    name = "sepia"
    summary = "affine colour map: two-stop gradient extrapolated over [0, inf) (S5.4)"
    params = (Param("gradient", "gradient", Gradient.parse(DEFAULT),
                    "exactly two colour stops over brightness, extrapolated linearly"),)
    default_inner = 1

    def validate(self) -> None:
        n = len(self.gradient.stops)
        if n != 2:
            raise StyleError(
                f"bad value {self.gradient.spec!r} for parameter 'gradient': sepia needs exactly "
                f"2 stops (got {n}) so that it stays affine in the radiance, which the unbiased "
                f"estimators rely on; use color_map for multi-stop gradients"
            )

    def affine(self) -> tuple[list[list[float]], list[float]]:
        """(A, b) with g(I) = A I + b: A a 3x3 matrix (list of rows), b a 3-vector."""
        (p0, c0), (p1, c1) = self.gradient.stops
        slope = [(b - a) / (p1 - p0) for a, b in zip(c0, c1)]
        A = [[s / 3.0] * 3 for s in slope]
        b = [a - s * p0 for a, s in zip(c0, slope)]
        return A, b

    def form(self):
        A, b = self.affine()
        return AffineForm(A, b)

    def apply(self, I: mi.Color3f, v: Vertex) -> mi.Color3f:
        return self.gradient.eval(brightness(I), extrapolate=True)
