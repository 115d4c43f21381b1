"""Owen-scrambled Sobol points (kernel/owen_sobol.py) against their definitions: Sobol's second
dimension from its direction numbers, computed bit by bit here; the (0, m, 2)-net property
counted over every elementary interval."""
import numpy as np
import pytest

from styletrace.gate import mi
from styletrace.kernel import owen_sobol as O


def direction_numbers_second() -> list[int]:
    """Sobol's second dimension: v_0 = 2^31, v_k = v_(k-1) xor (v_(k-1) >> 1) (primitive
    polynomial x + 1)."""
    v = [1 << 31]
    for _ in range(31):
        v.append(v[-1] ^ (v[-1] >> 1))
    return v


def test_second_dimension_is_sobols():
    index = np.arange(1 << 14, dtype=np.uint64)
    index = np.concatenate([index, np.array([0xFFFFFFFF, 0x80000001, 0x12345678], np.uint64)])
    expected = np.zeros_like(index)
    for k, v in enumerate(direction_numbers_second()):
        expected ^= np.where((index >> np.uint64(k)) & np.uint64(1), np.uint64(v), np.uint64(0))
    got = np.asarray(O.sobol_second(mi.UInt32(index.astype(np.uint32))), dtype=np.uint64)
    assert (got == expected).all()


def test_first_dimension_is_the_radical_inverse():
    index = np.arange(1 << 10, dtype=np.uint32)
    got = np.asarray(O.unit(O.sobol_first(mi.UInt32(index))), dtype=np.float64)
    expected = [sum(((i >> b) & 1) * 2.0 ** -(b + 1) for b in range(10)) for i in index]
    assert np.allclose(got, expected, atol=2 ** -24)


def elementary_counts(x: np.ndarray, y: np.ndarray, m: int):
    """For each split m = a + b, the number of points in each of the 2^a x 2^b intervals."""
    for a in range(m + 1):
        cell = (x * (1 << a)).astype(np.int64) * (1 << (m - a)) + (y * (1 << (m - a))).astype(
            np.int64)
        yield np.bincount(cell, minlength=1 << m)


@pytest.mark.parametrize("seed", [0, 1, 12345, 0xDEADBEEF])
@pytest.mark.parametrize("m", [2, 5, 8])
def test_prefixes_are_nets_whatever_the_seed(seed, m):
    x, y = O.point_2d(mi.UInt32(np.arange(1 << m, dtype=np.uint32)), mi.UInt32(seed))
    x, y = np.asarray(x, np.float64), np.asarray(y, np.float64)
    assert ((x >= 0) & (x < 1) & (y >= 0) & (y < 1)).all()
    for counts in elementary_counts(x, y, m):
        assert (counts == 1).all()


def test_one_dimension_is_stratified():
    u = np.asarray(O.point_1d(mi.UInt32(np.arange(64, dtype=np.uint32)), mi.UInt32(77)))
    assert (np.bincount((u * 64).astype(int), minlength=64) == 1).all()


def test_random_points_are_not_nets():
    """The net check has power: 256 independent uniform points miss it."""
    rng = np.random.default_rng(3)
    x, y = rng.random(256), rng.random(256)
    assert not all((c == 1).all() for c in elementary_counts(x, y, 8))


def test_seeds_scramble_independently():
    """The same index under 4096 different seeds: uniform, and the two coordinates and two seeds'
    points uncorrelated (|r| within 5 standard errors of 0, 1/sqrt(n) each)."""
    n = 4096
    seeds = O.mix(mi.UInt32(np.arange(n, dtype=np.uint32)))
    index = mi.UInt32(np.full(n, 5, np.uint32))
    x, y = (np.asarray(c, np.float64) for c in O.point_2d(index, seeds))
    x2, _ = (np.asarray(c, np.float64) for c in O.point_2d(index, O.mix(seeds)))
    bound = 5 / np.sqrt(n)
    assert abs(x.mean() - 0.5) < 5 * np.sqrt(1 / 12 / n)
    assert abs(np.corrcoef(x, y)[0, 1]) < bound
    assert abs(np.corrcoef(x, x2)[0, 1]) < bound
