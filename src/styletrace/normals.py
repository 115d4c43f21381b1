"""Vertex normals that are the same in every process.

`canonical_normals` recomputes a mesh's computed vertex normals on the host, in a fixed order,
with Mitsuba's formula: the sum over the faces at a vertex of the face's unit normal times its
interior angle there, normalized (Thürmer and Wüthrich). It replaces a mesh's normals only where
they agree with that formula to `TOLERANCE`; normals a file carries are left alone. Rationale:
docs/design/canonical_normals.md.
"""
from __future__ import annotations

from typing import Any

import numpy as np

#: largest difference per component between Mitsuba's computed normals and the host's (measured:
#: 1.7e-6 on the dragon); a file's own normals that differ by more are the author's and stay
TOLERANCE = 1e-4


def angle_weighted(positions: np.ndarray, faces: np.ndarray) -> np.ndarray:
    """Angle-weighted unit vertex normals of a triangle mesh, summed in a fixed order.

    Args:
        positions: V x 3 vertex positions (float64 recommended).
        faces: F x 3 integer vertex indices per triangle.

    Returns:
        V x 3 float64: per vertex, the normalized sum of its faces' unit normals weighted by the
        interior angle at the vertex; zero (never NaN) for vertices of degenerate faces only.
    """
    v = [positions[faces[:, i]] for i in range(3)]
    n = np.cross(v[1] - v[0], v[2] - v[0])
    length = np.linalg.norm(n, axis=1, keepdims=True)
    n = np.divide(n, length, out=np.zeros_like(n), where=length > 0)
    acc = np.zeros_like(positions)
    for i in range(3):
        a, b, c = v[i], v[(i + 1) % 3], v[(i + 2) % 3]
        e0, e1 = b - a, c - a
        l0, l1 = np.linalg.norm(e0, axis=1), np.linalg.norm(e1, axis=1)
        with np.errstate(divide="ignore", invalid="ignore"):
            cos = np.einsum("ij,ij->i", e0, e1) / (l0 * l1)
        angle = np.arccos(np.clip(np.nan_to_num(cos), -1.0, 1.0))
        w = n * angle[:, None]
        for k in range(3):  # bincount sums in index order: the same result on every run
            acc[:, k] += np.bincount(faces[:, i], weights=w[:, k], minlength=len(positions))
    length = np.linalg.norm(acc, axis=1, keepdims=True)
    return np.divide(acc, length, out=np.zeros_like(acc), where=length > 0)


def canonical_normals(scene: Any) -> int:
    """Replace every mesh's computed vertex normals by the host's deterministic ones.

    Only normals matching `angle_weighted` to TOLERANCE are replaced (a file's own are left);
    meshes inside shape groups are included.

    Args:
        scene: a loaded mi.Scene (its parameters are updated in place).

    Returns:
        How many meshes changed.
    """
    import mitsuba as mi
    params = mi.traverse(scene)
    changed = 0
    for key in [k for k in params.keys() if k.endswith(".vertex_normals")]:
        prefix = key[: -len("vertex_normals")]
        if prefix + "vertex_positions" not in params or prefix + "faces" not in params:
            continue
        loaded = np.array(params[key], dtype=np.float32).reshape(-1, 3)
        if loaded.size == 0:
            continue
        positions = np.array(params[prefix + "vertex_positions"], dtype=np.float64).reshape(-1, 3)
        faces = np.array(params[prefix + "faces"], dtype=np.int64).reshape(-1, 3)
        if len(positions) != len(loaded) or len(faces) == 0:
            continue
        ours = angle_weighted(positions, faces)
        # vertices of degenerate faces only: keep Mitsuba's value
        covered = np.linalg.norm(ours, axis=1) > 0
        if not np.all(np.abs(ours[covered] - loaded[covered]) <= TOLERANCE):
            continue  # the file's own normals
        out = loaded.copy()
        out[covered] = ours[covered].astype(np.float32)
        if np.array_equal(out, loaded):
            continue
        params[key] = type(params[key])(out.ravel())
        changed += 1
    if changed:
        params.update()
    return changed


__all__ = ["angle_weighted", "canonical_normals", "TOLERANCE"]
