"""`mesh.merge_corners`: equal corners merged bit for bit, different ones never, in order of first
appearance; checked against numpy's own unique on the rows' bytes."""
import numpy as np
import pytest

from styletrace.blender import mesh


def rows_with_repeats(n_distinct: int, n: int, width: int, seed: int = 0) -> np.ndarray:
    rng = np.random.default_rng(seed)
    distinct = rng.random((n_distinct, width), dtype=np.float32)
    distinct[0] = 0.0
    distinct[1] = -0.0  # equal as floats, different bits: kept apart
    return distinct[rng.integers(0, n_distinct, n)]


def as_bytes(rows: np.ndarray) -> np.ndarray:
    rows = np.ascontiguousarray(rows)
    return rows.view(np.dtype((np.void, rows.shape[1] * rows.itemsize))).ravel()


@pytest.mark.parametrize("width", [8, 6, 3])
def test_merges_equal_rows_only_in_order_of_first_appearance(width):
    table = rows_with_repeats(500, 20000, width)
    unique, inverse = mesh.merge_corners(table)
    assert unique.dtype == np.float32 and unique.shape[1] == width
    assert np.array_equal(as_bytes(unique[inverse]), as_bytes(table))
    assert len(unique) == len(np.unique(as_bytes(table)))  # every distinct row once
    first = [int(np.flatnonzero(inverse == k)[0]) for k in range(len(unique))]
    assert first == sorted(first)


def test_a_hash_collision_never_merges_different_rows(monkeypatch):
    monkeypatch.setattr(mesh, "_MIX", np.uint64(0))  # every row hashes to 0
    table = rows_with_repeats(50, 2000, 8, seed=1)
    unique, inverse = mesh.merge_corners(table)
    assert np.array_equal(as_bytes(unique[inverse]), as_bytes(table))
    assert len(unique) >= len(np.unique(as_bytes(table)))


def test_no_rows():
    unique, inverse = mesh.merge_corners(np.zeros((0, 8), np.float32))
    assert unique.shape == (0, 8) and inverse.shape == (0,)
