"""An independent random stream per SIMD lane for the inner samples of a stylized vertex.

A PCG32 stream per lane (initstate from two of the scene sampler's numbers, stream index from the
lane), used for every random decision below the first hit: the scene's sampler only places the
camera ray (Mitsuba's samplers do not give the children of a symbolic loop independent numbers).
It offers the two Sampler methods the path tracer uses, `next_1d` and `next_2d`, and is a Dr.Jit
struct, so it travels in loop state like Mitsuba's own samplers.
Design: docs/design/lane_sampler.md.
"""
from __future__ import annotations

from styletrace.gate import dr, mi


class LaneSampler:
    """Per-lane PCG32 random numbers, with the Sampler methods the path tracer uses.

    Args:
        rng: the lanes' generator (mi.PCG32); None: a default-seeded one.
    """
    DRJIT_STRUCT = {"rng": mi.PCG32}

    def __init__(self, rng: mi.PCG32 | None = None):
        self.rng = rng if rng is not None else mi.PCG32()

    @staticmethod
    def seeded_from(sampler: mi.Sampler, width: int) -> "LaneSampler":
        """A stream per lane, seeded from two of `sampler`'s numbers; the lane is the stream index.

        Args:
            sampler: the scene's sampler, seeded for the wavefront (mi.Sampler).
            width: the number of lanes.

        Returns:
            LaneSampler.
        """
        hi = dr.reinterpret_array(mi.UInt32, sampler.next_1d())
        lo = dr.reinterpret_array(mi.UInt32, sampler.next_1d())
        state = (mi.UInt64(hi) << 32) | mi.UInt64(lo)
        return LaneSampler(mi.PCG32(width, initstate=state, initseq=dr.arange(mi.UInt64, width)))

    def split(self) -> "LaneSampler":
        """The stream the next child draws from: this one (its numbers follow the previous
        child's; `sequence_sampler.SequenceSampler.split` gives each child a stream of its own).

        Returns:
            LaneSampler (self).
        """
        return self

    def next_1d(self, active=True) -> mi.Float:
        """One uniform number per lane, in [0, 1).

        Args:
            active: the lanes that draw (mi.Bool or True).

        Returns:
            mi.Float.
        """
        return self.rng.next_float32(active)

    def next_2d(self, active=True) -> mi.Point2f:
        """Two uniform numbers per lane, in [0, 1)^2.

        Args:
            active: the lanes that draw (mi.Bool or True).

        Returns:
            mi.Point2f.
        """
        return mi.Point2f(self.rng.next_float32(active), self.rng.next_float32(active))
