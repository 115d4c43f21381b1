"""An independent random stream per SIMD lane for the inner samples of a stylized vertex.

The n children of a stylized vertex must be independent draws: the unbiased estimators rely on it
(products and U-statistics of samples) and direct application's bias depends on it. Mitsuba's
samplers stratify across camera samples, not across the iterations of a symbolic loop, and some of
them cannot advance inside one at all: `ldsampler`'s dimension counter is a trace-time constant, so
all n children receive the same numbers (measured: Var(<I>_n) does not fall with n), and
`orthogonal` correlates them. So the scene's sampler only places the camera ray and seeds this
generator: a PCG32 stream per lane (initstate from two of the scene sampler's numbers, stream index
from the lane), used for every random decision below the first hit.

It offers the two Sampler methods the path tracer uses, `next_1d` and `next_2d`, and is a Dr.Jit
struct, so it travels in loop state like Mitsuba's own samplers.
"""
from __future__ import annotations

from styletrace.gate import dr, mi


class LaneSampler:
    DRJIT_STRUCT = {"rng": mi.PCG32}

    def __init__(self, rng: mi.PCG32 | None = None):
        self.rng = rng if rng is not None else mi.PCG32()

    @staticmethod
    def seeded_from(sampler: mi.Sampler, width: int) -> "LaneSampler":
        hi = dr.reinterpret_array(mi.UInt32, sampler.next_1d())
        lo = dr.reinterpret_array(mi.UInt32, sampler.next_1d())
        state = (mi.UInt64(hi) << 32) | mi.UInt64(lo)
        return LaneSampler(mi.PCG32(width, initstate=state, initseq=dr.arange(mi.UInt64, width)))

    def next_1d(self, active=True) -> mi.Float:
        return self.rng.next_float32(active)

    def next_2d(self, active=True) -> mi.Point2f:
        return mi.Point2f(self.rng.next_float32(active), self.rng.next_float32(active))
