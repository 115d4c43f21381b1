"""Expansion points: a fixed b, or b estimated from separate pilot samples.

Reference: West & Mukherjee, supplement S2.3 ("one reasonable choice for the expansion point b is an
estimate <I>"). Series estimators stay unbiased only if b is independent of the term samples, so the
pilot consumes its own first n samples.

`Pilot(n=1, lo=None, hi=None, scale=1, spread=0)`: b = clamp(max(scale mean, spread mean(x^2) /
mean(x)), lo, hi) over n pilot draws, then `Series.clamp_center`. `PerLane(b)`: b given per lane
(the renderer's `expansion_pass`), clamped as a pilot's. Why scale and spread:
docs/design/power_series.md.
"""
from __future__ import annotations

import math

import numpy as np

from styletrace.estimators import arrays as A
from styletrace.estimators.base import check_count

__all__ = ["Pilot", "PerLane", "ExpansionPoint"]


class Pilot:
    """b from the estimate's own first n draws (the pilot), independent of its term samples:
    b = clamp(max(scale mean, spread mean(x^2) / mean(x)), lo, hi), then `Series.clamp_center`.

    Args:
        n: pilot draws (>= 1).
        lo, hi: clamp bounds on b (finite, lo < hi), or None: unbounded on that side.
        scale: factor on the pilot mean (finite, > 0).
        spread: 0, or aims b at spread E[x^2] / E[x] where that is larger (finite, >= 0).

    Raises:
        ValueError: any of them out of range.
    """

    def __init__(self, n: int = 1, lo=None, hi=None, scale: float = 1.0, spread: float = 0.0):
        self.n = check_count("pilot n", n)
        if not (isinstance(scale, (int, float)) and math.isfinite(scale) and scale > 0):
            raise ValueError(f"pilot scale must be a finite number > 0, got {scale!r}")
        self.scale = float(scale)
        if isinstance(spread, bool) or not (isinstance(spread, (int, float))
                                            and math.isfinite(spread) and spread >= 0):
            raise ValueError(f"pilot spread must be a finite number >= 0, got {spread!r}")
        self.spread = float(spread)
        for name, v in (("lo", lo), ("hi", hi)):
            if v is not None and not (isinstance(v, (int, float)) and math.isfinite(v)):
                raise ValueError(f"pilot {name} must be a finite number or None, got {v!r}")
        if lo is not None and hi is not None and not lo < hi:
            raise ValueError(f"pilot clamp needs lo < hi, got lo={lo}, hi={hi}")
        self.lo, self.hi = lo, hi

    def __repr__(self):
        return (f"Pilot(n={self.n}" + (f", scale={self.scale:g}" if self.scale != 1.0 else "")
                + (f", spread={self.spread:g}" if self.spread else "") + ")")


class PerLane:
    """b per lane, computed by the caller from samples independent of the estimate's own (the
    renderer's `expansion_pass`); clamped as a pilot's b.

    Args:
        b: per-lane expansion points (Dr.Jit value, or numpy with one row per lane).
        lo: a floor on b (finite), or None.

    Raises:
        ValueError: lo not a finite number or None.
    """

    def __init__(self, b, lo=None):
        if lo is not None and not (isinstance(lo, (int, float)) and math.isfinite(lo)):
            raise ValueError(f"per-lane b floor lo must be a finite number or None, got {lo!r}")
        self.b, self.lo = b, lo

    def __repr__(self):
        return "PerLane(...)"


class ExpansionPoint:
    """The b of an estimator: fixed (checked against the series) or a pilot (clamped per lane).

    Args:
        b: a Pilot, a PerLane, a fixed float or per-channel vector, or None (`default`).
        default: the fixed b where b is None.
        series: the `coefficients.Series` expanded (checks a fixed b, clamps the others), or None.

    Raises:
        ValueError: a fixed b not finite, not 0-D or 1-D, or outside the series' region.
    """

    def __init__(self, b, default=0.0, series=None):
        self.series = series
        self.lane = None
        if isinstance(b, Pilot):
            self.pilot, self.fixed = b, None
        elif isinstance(b, PerLane):
            self.pilot, self.fixed, self.lane = None, None, b
        else:
            self.pilot = None
            b = default if b is None else b
            arr = np.asarray(b, dtype=np.float64)
            if arr.ndim > 1 or not np.all(np.isfinite(arr)):
                raise ValueError("expansion point b must be a finite scalar, a per-channel vector "
                                 f"or Pilot(...), got {b!r}")
            if series is not None:
                series.check_center(arr)
            self.fixed = arr

    @property
    def draws(self) -> int:
        """The draws of X the pilot consumes (0 for a fixed centre)."""
        return self.pilot.n if self.pilot else 0

    def describe(self) -> str:
        if self.pilot:
            return f"b=pilot({self.pilot.n})"
        if self.lane:
            return "b=per-lane"
        return (f"b={np.array2string(self.fixed, precision=3)}" if self.fixed.ndim
                else f"b={float(self.fixed):g}")

    # -- kernel side --------------------------------------------------------------------------
    def start(self, ctx) -> dict:
        """The expansion point's part of an estimator's state.

        Args:
            ctx: the run's `base.Context`.

        Returns:
            {} (fixed b), {"b": ...} (per lane), or the pilot's running sums with b = 1 until done.
        """
        if self.lane:
            return {"b": self._lane_b(ctx)}
        if not self.pilot:
            return {}
        # b = 1 until the pilot is done keeps the unused (masked) series arithmetic finite
        state = {"psum": ctx.vzero(), "pcount": ctx.lane(0.0), "b": ctx.value_array(1.0)}
        if self.pilot.spread:
            state["psum2"] = ctx.vzero()
        return state

    def in_pilot(self, state):
        """Lanes still collecting pilot samples (None when b is fixed).

        Args:
            state: the estimator's state.

        Returns:
            A per-lane mask, or None without a pilot.
        """
        if not self.pilot:
            return None
        return state["pcount"] < self.pilot.n

    def feed(self, ctx, state, x, mask):
        """Take x on the pilot lanes of mask (a pilot's b only).

        Args:
            ctx: the run's `base.Context`; state: the estimator's state.
            x: the draw; mask: the lanes that drew it.

        Returns:
            (state, done): the new state, and the lanes whose b became known with this draw.
        """
        state = dict(state)
        take = mask & (state["pcount"] < self.pilot.n)
        state["psum"] = A.select(take, state["psum"] + x, state["psum"])
        state["pcount"] = A.select(take, state["pcount"] + 1.0, state["pcount"])
        done = take & (state["pcount"] >= self.pilot.n)
        b = state["psum"] * (self.pilot.scale / self.pilot.n)
        if self.pilot.spread:
            state["psum2"] = A.select(take, state["psum2"] + x * x, state["psum2"])
            pos = state["psum"] > 0.0
            ratio = state["psum2"] / A.select(pos, state["psum"], state["psum"] * 0.0 + 1.0)
            b = A.select(pos, A.maximum(b, ratio * self.pilot.spread), b)
        b = A.clip(b, self.pilot.lo, self.pilot.hi)
        if self.series is not None:
            b = self.series.clamp_center(b)
        state["b"] = A.select(done, b, state["b"])
        return state, done

    def _lane_b(self, ctx):
        b = self.lane.b
        if not ctx.is_drjit:
            b = np.asarray(b, dtype=np.float64).reshape(ctx.lanes, -1)
        b = A.clip(b, self.lane.lo, None)
        if self.series is not None:
            b = self.series.clamp_center(b)
        return ctx.vzero() + b

    def value(self, ctx, state):
        """b as a value array (pilot, per lane) or a constant (fixed).

        Args:
            ctx: the run's `base.Context`; state: the estimator's state.

        Returns:
            The per-lane b, or `Context.vconst` of the fixed b.
        """
        if self.pilot or self.lane:
            return state["b"]
        return ctx.vconst(self.fixed)
