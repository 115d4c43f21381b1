"""Low-discrepancy random numbers per lane: a padded Owen-scrambled Sobol sequence over the
camera samples of a pixel, with an independent stream for every child of a stylized vertex.

    lanes = SequenceSampler(key, index, dim)  # key: the pixel's stream, index: its sample number
    u = lanes.next_1d(); uv = lanes.next_2d() # dimension `dim`, then the next
    child = lanes.split()                     # a child's own stream (and lanes moves on)

Dimension d of a lane is `owen_sobol.point_1d` or `point_2d` of its sample index under the seed
hash(key, d): across the camera samples of one pixel each dimension (pair) is a scrambled Sobol
(0, 2)-sequence, and different dimensions are independent (padding: the shuffle differs per
dimension). The children at a stylized vertex must be independent draws (the unbiased estimators'
products and U-statistics, direct application's bias): `split` gives each child the stream
hash(key, k) for the k-th child, so child k of every camera sample continues one sequence (its
samples are stratified across the pixel's camera samples), while the children of one camera
sample share no numbers. It offers the Sampler methods the path tracer uses, and is a Dr.Jit
struct, so it travels in loop state; the dimension is a loop variable, so every bounce and every
child of a symbolic loop draws new dimensions (a Mitsuba sampler's dimension counter is a
trace-time constant: docs/design/lane_sampler.md).
Design: docs/design/sequence_sampler.md.
"""
from __future__ import annotations

from styletrace.gate import dr, mi
from styletrace.kernel.owen_sobol import mix, point_1d, point_2d

#: odd constants that separate the hash inputs of dimensions and children
_DIM, _CHILD = 0x9E3779B9, 0x85EBCA6B


class SequenceSampler:
    """A lane's sequence (module docstring).

    Args:
        key: the stream's key per lane (mi.UInt32): its pixel and the render's seed, hashed.
        index: each lane's sample number in its pixel (mi.UInt32).
        dim: the next dimension to draw (mi.UInt32).
        spawned: children split off so far (mi.UInt32).
    """
    DRJIT_STRUCT = {"key": mi.UInt32, "index": mi.UInt32, "dim": mi.UInt32,
                    "spawned": mi.UInt32}

    def __init__(self, key=None, index=None, dim=None, spawned=None):
        self.key = mi.UInt32(0 if key is None else key)
        self.index = mi.UInt32(0 if index is None else index)
        self.dim = mi.UInt32(0 if dim is None else dim)
        self.spawned = mi.UInt32(0 if spawned is None else spawned)

    def _seed(self) -> mi.UInt32:
        seed = mix(self.key + self.dim * _DIM)
        self.dim = self.dim + 1
        return seed

    def next_1d(self, active=True) -> mi.Float:
        """One number per lane in [0, 1): the next dimension (every lane moves on, so a dimension
        means the same decision in every sample).

        Args:
            active: accepted for the Sampler interface; all lanes advance.

        Returns:
            mi.Float.
        """
        return point_1d(self.index, self._seed())

    def next_2d(self, active=True) -> mi.Point2f:
        """Two numbers per lane in [0, 1)^2 from one dimension pair.

        Args:
            active: accepted for the Sampler interface; all lanes advance.

        Returns:
            mi.Point2f.
        """
        x, y = point_2d(self.index, self._seed())
        return mi.Point2f(x, y)

    def split(self) -> "SequenceSampler":
        """The next child's own stream, from its first dimension; this stream counts the child.

        Returns:
            SequenceSampler.
        """
        child = SequenceSampler(mix(self.key ^ mix(self.spawned * _CHILD + 1)), self.index,
                                counter(0, self.key), counter(0, self.key))
        self.spawned = self.spawned + 1
        return child


def counter(value: int, like) -> mi.UInt32:
    """A counter's start as an opaque array as wide as `like`: a literal that a symbolic loop
    changes makes Dr.Jit trace the loop's body again, and nested loops would trace 2^depth times.

    Args:
        value: the start. like: an array of the lanes' width.

    Returns:
        mi.UInt32.
    """
    return dr.opaque(mi.UInt32, value, dr.width(like))


def pixel_key(seed, tile, pixel) -> mi.UInt32:
    """The stream key of a pixel: a hash of the render's seed, its tile and the pixel's index
    in the tile.

    Args:
        seed, tile: mi.UInt32 or int. pixel: mi.UInt32.

    Returns:
        mi.UInt32.
    """
    return mix(mix(mix(mi.UInt32(seed)) ^ mi.UInt32(tile)) ^ mi.UInt32(pixel))


__all__ = ["SequenceSampler", "counter", "pixel_key"]
