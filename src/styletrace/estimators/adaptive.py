"""Direct application with adaptive stopping: n0 children, more only where the error is large.

Reference: West & Mukherjee, Eqs. 19 and 21; Broadie, Du, Moallemi (2011). Each lane draws n0
samples, then one more while n < n_max and
    step:    |m - tau_k| < t_(n-1)(z) s / sqrt(n) for some threshold tau_k, or
    smooth:  max_c |g_c''(<I>_n)| s^2 / (2n) > bias,
m and s^2 the running brightness mean and variance. The estimate is g(<I>_n).

`AdaptiveDirect(g, n0, n_max, thresholds=(), curvature=None, z=2, bias=1e-3)`; after `run`,
`stats` holds per-lane `children`, `variance` and `bias` (docs/design/adaptive_stopping.md).
"""
from __future__ import annotations

import numpy as np

from styletrace.estimators import arrays as A
from styletrace.estimators.base import Context, Estimator, check_count

__all__ = ["AdaptiveDirect"]


class AdaptiveDirect(Estimator):
    """g(<I>_n), n chosen per lane by the stopping rules of the module doc.

    Args:
        g: callable g(x) -> y, array-generic as for ``Direct``.
        n0, n_max: 1 <= n0 <= n_max; n0 == n_max is a fixed count that still reports statistics.
        thresholds: brightnesses where g jumps: numbers or per-lane arrays (+inf: none there).
        curvature: None (no smooth rule), or (mean, h) -> g''(mean) per channel, h the standard
            error per lane (on numpy it must not close over per-lane data: lanes are compacted).
        z: the band's confidence in standard normal deviations; bias: the smooth rule's target.

    Raises:
        ValueError: g or curvature not callable, bad counts, z or bias not positive and finite.
    """

    def __init__(self, g, n0: int, n_max: int, thresholds=(), curvature=None, z: float = 2.0,
                 bias: float = 1e-3):
        if not callable(g):
            raise ValueError(f"g must be a callable g(x) -> y, got {g!r}")
        if curvature is not None and not callable(curvature):
            raise ValueError("curvature must be None or a callable (mean, h) -> g''(mean), got "
                             f"{curvature!r}")
        self.n0 = check_count("n0", n0)
        self.n_max = check_count("n_max", n_max, self.n0)
        if not (np.isfinite(z) and z > 0) or not (np.isfinite(bias) and bias > 0):
            raise ValueError(f"z and bias must be positive and finite, got z={z!r}, bias={bias!r}")
        self.g, self.curvature, self.z, self.target = g, curvature, float(z), float(bias)
        self.thresholds = tuple(thresholds)
        self.stats = None
        self.name = f"direct(n={self.n0}:{self.n_max})"

    # -- running statistics ---------------------------------------------------------------------
    def start(self, ctx: Context, carry):
        zero = ctx.lane(0.0)
        state = {
            "sum": ctx.vzero(),
            "count": zero,
            "mean_u": zero,
            "m2_u": zero,
            # per-lane copies, so that numpy's lane compaction carries them along with the
            # lanes
            "tau": tuple(
                zero + (t if not isinstance(t, np.ndarray) else np.reshape(t, (-1, 1)))
                for t in self.thresholds
            ),
        }
        return state, carry

    def feed(self, ctx, state, x, mask, carry):
        state = dict(state)
        n = state["count"] + 1.0
        u = A.channel_mean(x)
        delta = u - state["mean_u"]
        mean_u = state["mean_u"] + delta / n
        m2_u = state["m2_u"] + delta * (u - mean_u)
        state["sum"] = A.select(mask, state["sum"] + x, state["sum"])
        state["count"] = A.select(mask, n, state["count"])
        state["mean_u"] = A.select(mask, mean_u, state["mean_u"])
        state["m2_u"] = A.select(mask, m2_u, state["m2_u"])
        return state, carry

    def mean(self, state):
        """<I>_n, the mean of the lane's children.

        Args:
            state: the loop state.

        Returns:
            The per-lane mean value (like x).
        """
        # as Direct computes it: a fixed count gives Direct's estimate bit for bit
        if self.n0 == self.n_max:
            return state["sum"] * (1.0 / self.n0)
        return state["sum"] / A.maximum(state["count"], 1.0)

    def variance(self, state):
        """Sample variance of the children's brightness (0 below 2 children).

        Args:
            state: the loop state.

        Returns:
            s^2 per lane (a per-lane scalar).
        """
        n = state["count"]
        return A.select(n > 1.5, A.maximum(state["m2_u"], 0.0) / A.maximum(n - 1.0, 1.0), 0.0 * n)

    def predicted_bias(self, state, signed: bool):
        """g''(<I>_n) s^2 / (2n), the Eq. 21 prediction (0 without ``curvature``).

        Args:
            state: the loop state.
            signed: True: the channels' signed mean (the AOV); False: the largest per-channel
                magnitude (the stopping rule).

        Returns:
            A per-lane scalar.
        """
        n = A.maximum(state["count"], 1.0)
        var = self.variance(state)
        if self.curvature is None:
            return 0.0 * var
        curv = self.curvature(self.mean(state), A.sqrt(var / n))
        per = A.channel_mean(curv) if signed else A.hmax(A.abs(curv))
        return per * var / (2.0 * n)

    def band_width(self, n):
        """The band's half-width in standard errors at n children: Student's t quantile with n - 1
        degrees of freedom at z's normal confidence (s is estimated from the same few children), by
        its expansion in 1/v (Abramowitz and Stegun 26.7.5, four terms: 3.303 for z = 2, v = 3,
        where the exact quantile is 3.307), tending to z as n grows.

        Args:
            n: the children per lane (n < 2 is taken as 2).

        Returns:
            t_(n-1)(z) per lane.
        """
        z = self.z
        w = 1.0 / A.maximum(n - 1.0, 1.0)
        terms = [(z ** 3 + z) / 4.0, (5 * z ** 5 + 16 * z ** 3 + 3 * z) / 96.0,
                 (3 * z ** 7 + 19 * z ** 5 + 17 * z ** 3 - 15 * z) / 384.0,
                 (79 * z ** 9 + 776 * z ** 7 + 1482 * z ** 5 - 1920 * z ** 3 - 945 * z) / 92160.0]
        return z + w * (terms[0] + w * (terms[1] + w * (terms[2] + w * terms[3])))

    def needs_more(self, state):
        """Whether a lane's step or smooth rule asks for another child (n0 and n_max aside).

        Args:
            state: the loop state.

        Returns:
            A per-lane mask.
        """
        n = A.maximum(state["count"], 1.0)
        band = self.band_width(n) * A.sqrt(self.variance(state) / n)
        near = state["count"] < 0.0  # all False, as a per-lane mask
        for tau in state["tau"]:
            near = near | (A.abs(state["mean_u"] - tau) < band)
        if self.curvature is not None:
            near = near | (self.predicted_bias(state, signed=False) > self.target)
        return near

    # -- the protocol ---------------------------------------------------------------------------
    def wants(self, ctx, state):
        count = state["count"]
        return (count < self.n0) | ((count < self.n_max) & self.needs_more(state))

    def value(self, ctx, state):
        return self.g(self.mean(state))

    def exact(self, I):
        return self.g(I)

    @property
    def mean_draws(self):
        return None if self.n0 != self.n_max else float(self.n0)

    @property
    def fixed_draws(self):
        return self.n0 == self.n_max

    def run(self, draw, carry, uniform, active=None, *, like=None):
        """As ``Estimator.run``; afterwards ``self.stats`` holds this run's per-lane statistics."""
        def observe(state):
            self.stats = {"children": state["count"], "variance": self.variance(state),
                          "bias": self.predicted_bias(state, signed=True)}
        return self._run(draw, carry, uniform, active, like, observe)
