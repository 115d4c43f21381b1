"""kernel/world_grid.py: world-space neighbours, checked against numpy brute force."""
import numpy as np
import pytest

import styletrace
from styletrace.gate import dr, mi
from styletrace.kernel.world_grid import WorldGrid, cell_keys, density_h

styletrace.init()

K = 8


def grid_of(P, valid, h, jitter, start, normals=None):
    n = P.shape[1]
    p = mi.Point3f(*[mi.Float(P[i].astype(np.float32)) for i in range(3)])
    grid = WorldGrid(
        p,
        mi.Bool(valid),
        h,
        K,
        mi.Point3f(*[mi.Float(jitter[i].astype(np.float32)) for i in range(3)]),
        mi.Float(start.astype(np.float32)),
        [0.0, 0.0, 0.0],
    )
    N = normals if normals is not None else np.tile([[0.0], [0.0], [1.0]], (1, n))
    mask = grid.accepted(dr.zeros(mi.Int32, n), dr.zeros(mi.BSDFPtr, n), mi.Bool(valid),
                         mi.Vector3f(*[mi.Float(N[i].astype(np.float32)) for i in range(3)]), 0.9)
    slots = []
    for q in range(K + 1):
        at, found = grid.neighbour(mi.UInt32(q))
        slots.append((np.asarray(at, dtype=np.int64), np.asarray(found, dtype=bool)))
    return grid, np.asarray(mask, dtype=np.uint64), slots


@pytest.fixture(scope="module")
def points():
    """Points on two planes (z = 0.3 and a slanted one) in the unit cube, some invalid."""
    rng = np.random.default_rng(1)
    n = 3000
    P = rng.random((3, n))
    P[2, : n // 2] = 0.3
    P[2, n // 2:] = 0.2 + 0.5 * P[0, n // 2:]
    valid = rng.random(n) < 0.9
    return P.astype(np.float32).astype(np.float64), valid, rng.random((3, n)), rng.random(n)


def test_candidates_are_the_jittered_cell_and_accepted_within_h(points):
    P, valid, jitter, start = points
    h = 0.05
    grid, mask, slots = grid_of(P, valid, h, jitter, start)
    corner = np.zeros((3, 1)) - h
    keys = cell_keys(P, corner, h)
    lookup = cell_keys(P + (jitter.astype(np.float32) - 0.5) * h, corner, h)
    checked = 0
    for i in range(P.shape[1]):
        cell = set(np.flatnonzero(valid & (keys == lookup[i])).tolist()) - {i}
        found = {int(slots[q][0][i]) for q in range(1, K + 1) if slots[q][1][i]}
        assert found <= cell, f"vertex {i}: candidates outside its jittered cell"
        assert len(found) == min(len(cell), K) or (
            i in np.flatnonzero(valid & (keys == lookup[i])) and len(found) == min(len(cell), K - 1)
        ), f"vertex {i}"
        accepted = {int(slots[q][0][i]) for q in range(K + 1) if int(mask[i]) >> q & 1}
        if not valid[i]:
            assert accepted == set()
            continue
        d = np.linalg.norm(P[:, sorted(accepted)] - P[:, [i]], axis=0) if accepted else np.zeros(0)
        assert np.all(d <= h * (1 + 1e-5)), f"vertex {i}: a neighbour beyond h"
        near = {j for j in found if np.linalg.norm(P[:, j] - P[:, i]) <= h * (1 - 1e-5)}
        assert near <= accepted, f"vertex {i}: a candidate within h rejected"
        if len(cell) <= K - 1:  # every vertex of the cell within h is found
            brute = {j for j in cell if np.linalg.norm(P[:, j] - P[:, i]) <= h * (1 - 1e-5)}
            assert brute <= accepted
            checked += 1
        assert i in accepted
    assert checked > 500
    # pools are not trivially empty
    assert np.mean([bin(int(x)).count("1") for x in mask[valid]]) > 2


def test_normals_must_agree(points):
    P, valid, jitter, start = points
    normals = np.tile([[0.0], [0.0], [1.0]], (1, P.shape[1]))
    normals[:, ::2] = [[0.0], [1.0], [0.0]]
    _, mask, slots = grid_of(P, valid, 0.05, jitter, start, normals)
    for i in range(0, P.shape[1], 7):
        for q in range(1, K + 1):
            if int(mask[i]) >> q & 1:
                assert (slots[q][0][i] - i) % 2 == 0


def test_density_h_holds_about_k_per_cell(points):
    P, valid, _, _ = points
    p = mi.Point3f(*[mi.Float(P[i].astype(np.float32)) for i in range(3)])
    h = density_h(p, mi.Bool(valid), K, [0.0, 0.0, 0.0], 1e-4, np.sqrt(3.0))
    _, inverse, counts = np.unique(cell_keys(P[:, valid], np.zeros((3, 1)), h), return_inverse=True,
                                   return_counts=True)
    assert 0.5 * (K + 1) < counts[inverse].mean() < 2.0 * (K + 1)
