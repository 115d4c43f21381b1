"""Owen-scrambled Sobol points in one and two dimensions, hash-based, per lane.

    u = point_1d(index, seed)          # mi.Float in [0, 1)
    u, v = point_2d(index, seed)       # two mi.Float in [0, 1)

The first two dimensions of Sobol's sequence (a (0, 2)-sequence in base 2) with the sample index
shuffled and each coordinate scrambled by nested uniform (Owen) scrambling, both approximated by
the hash-based permutation of "Practical Hash-based Owen Scrambling" (Brent Burley, JCGT 2020).
A seed picks the shuffle and the scrambles, so points of different seeds are independent, and the
first 2^m indices of one seed form a (0, m, 2)-net: every one of the 2^m elementary intervals of
area 2^-m holds exactly one of them, whatever the seed (the shuffle maps them onto an aligned
block of 2^m consecutive Sobol indices). `sequence_sampler.py` pads these pairs into as many
dimensions as a path needs.
Design: docs/design/sequence_sampler.md.
"""
from __future__ import annotations

from styletrace.gate import dr, mi

#: the multipliers of the hash-based nested uniform scramble (Burley 2020, after Laine and Karras)
_SCRAMBLE = (0x6C50B47C, 0xB82F1E52, 0xC7AFE638, 0x8D22F6E6)
#: (shift, mask) of the five steps of the superset transform that gives Sobol's second dimension
_PASCAL = ((1, 0x55555555), (2, 0x33333333), (4, 0x0F0F0F0F), (8, 0x00FF00FF), (16, 0x0000FFFF))
#: seed offsets of the index shuffle and of the two coordinates' scrambles
_SHUFFLE, _FIRST, _SECOND = 0x2545F491, 0x9E3779B9, 0x7F4A7C15


def mix(x) -> mi.UInt32:
    """A 32-bit integer hash with full avalanche (xor-shift-multiply, the "lowbias32" constants).

    Args:
        x: mi.UInt32 (or an int).

    Returns:
        mi.UInt32.
    """
    x = mi.UInt32(x)
    x ^= x >> 16
    x *= 0x7FEB352D
    x ^= x >> 15
    x *= 0x846CA68B
    x ^= x >> 16
    return x


def _permute(x, seed) -> mi.UInt32:
    # each bit flipped by a hash of the bits below it: nested uniform scrambling of the bits
    # read from the least significant up
    x = x + seed
    for k in _SCRAMBLE:
        x ^= x * k
    return x


def scramble(x, seed) -> mi.UInt32:
    """Nested uniform scrambling of a 32-bit binary fraction (most significant digit first): each
    digit is flipped by a hash of the seed and the digits before it.

    Args:
        x: mi.UInt32, the fraction's digits. seed: mi.UInt32.

    Returns:
        mi.UInt32.
    """
    return dr.brev(_permute(dr.brev(x), seed))


def sobol_first(index) -> mi.UInt32:
    """Sobol's first dimension (van der Corput's radical inverse) of `index`, as a 32-bit fraction.

    Args:
        index: mi.UInt32.

    Returns:
        mi.UInt32.
    """
    return dr.brev(mi.UInt32(index))


def sobol_second(index) -> mi.UInt32:
    """Sobol's second dimension of `index`, as a 32-bit fraction.

    Its generator matrix is Pascal's triangle mod 2: digit m is the parity of the index's bits k
    with C(k, m) odd, that is with k a superset of m (Lucas), five xor-shift steps.

    Args:
        index: mi.UInt32.

    Returns:
        mi.UInt32.
    """
    z = mi.UInt32(index)
    for shift, mask in _PASCAL:
        z ^= (z >> shift) & mask
    return dr.brev(z)


def unit(x) -> mi.Float:
    """A 32-bit fraction as a float in [0, 1) (its 24 leading digits, exactly).

    Args:
        x: mi.UInt32.

    Returns:
        mi.Float.
    """
    return mi.Float(x >> 8) * (1.0 / (1 << 24))


def shuffled(index, seed) -> mi.UInt32:
    """The seed's permutation of the sample indices: aligned blocks of 2^m indices map onto
    aligned blocks of 2^m (so prefixes of 2^m samples stay nets).

    Args:
        index: mi.UInt32. seed: mi.UInt32.

    Returns:
        mi.UInt32.
    """
    return scramble(mi.UInt32(index), seed ^ _SHUFFLE)


def point_1d(index, seed) -> mi.Float:
    """The `index`-th point of the seed's scrambled one-dimensional sequence (stratified: the first
    2^m points hold one point in each interval [k 2^-m, (k + 1) 2^-m)).

    Args:
        index: mi.UInt32, the sample's number. seed: mi.UInt32.

    Returns:
        mi.Float in [0, 1).
    """
    # scramble(sobol_first(i)) = brev(permute(i)): the bit reversals cancel
    return unit(dr.brev(_permute(shuffled(index, seed), mix(seed ^ _FIRST))))


def point_2d(index, seed) -> tuple[mi.Float, mi.Float]:
    """The `index`-th point of the seed's scrambled (0, 2)-sequence (module docstring).

    Args:
        index: mi.UInt32, the sample's number. seed: mi.UInt32.

    Returns:
        (mi.Float, mi.Float), each in [0, 1).
    """
    i = shuffled(index, seed)
    x = dr.brev(_permute(i, mix(seed ^ _FIRST)))
    y = scramble(sobol_second(i), mix(seed ^ _SECOND))
    return unit(x), unit(y)


__all__ = ["mix", "scramble", "sobol_first", "sobol_second", "unit", "shuffled", "point_1d",
           "point_2d"]
