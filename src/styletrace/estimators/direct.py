"""Direct application: g applied to the mean of n samples (biased, consistent).

Reference: West & Mukherjee, Eq. 19:  <g(I)>_direct = g(<I>_n),  <I>_n = (1/n) sum_i x_i.
Its first-order bias (Eq. 21) is g''(I) Var[x] / (2n) per channel
(docs/design/adaptive_stopping.md).

`Direct(g, n, comb=False, cap=None)`: g array-generic; n >= 1 samples; comb: a stratified comb
(docs/design/comb_stratification.md); cap: (k, floor), the firefly control of `affine.MeanOfN`.
"""
from __future__ import annotations

from styletrace.estimators.affine import MeanOfN

__all__ = ["Direct"]


class Direct(MeanOfN):
    """g(<I>_n), the mean of n samples passed through g (biased O(1/n), consistent).

    Args:
        g: callable g(x) -> y, array-generic (numpy or Dr.Jit values).
        n: samples per estimate (>= 1); comb: stratify them with the comb.
        cap: (k, floor), the firefly control of `affine.MeanOfN`, or None.

    Raises:
        ValueError: g not callable, n not an integer >= 1, or a bad cap.
    """

    def __init__(self, g, n: int, comb: bool = False, cap: tuple[float, float] | None = None):
        if not callable(g):
            raise ValueError(f"g must be a callable g(x) -> y, got {g!r}")
        super().__init__(n, comb, cap)
        self.g = g
        self.name = f"direct(n={self.n}{', comb' if comb else ''}{', capped' if self.cap else ''})"

    def value(self, ctx, state):
        return self.g(self.mean(state))

    def exact(self, I):
        return self.g(I)
