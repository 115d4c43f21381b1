"""Evaluated Blender meshes -> Mitsuba meshes in memory, one per material slot.

The evaluated object's mesh (modifiers applied) is read with `foreach_get` into numpy: the loop
triangles, their corners' positions, loop ("corner") normals and the active UV map. Corner normals
are what Blender shades with, so smooth, flat and auto-smooth edges come out as Blender shows them.
Corners that share position, normal and UV are merged again (`np.unique`), so a smooth mesh keeps
about one vertex per vertex.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from styletrace.blender import units


@dataclass
class Part:
    """The triangles of one material slot: float32 positions/normals (N x 3), uvs (N x 2) or None,
    uint32 faces (F x 3); `slot` is the material index."""

    slot: int
    positions: np.ndarray
    normals: np.ndarray
    uvs: np.ndarray | None
    faces: np.ndarray


def _get(collection, attr: str, width: int, dtype) -> np.ndarray:
    out = np.empty(len(collection) * width, dtype=dtype)
    collection.foreach_get(attr, out)
    return out.reshape(-1, width) if width > 1 else out


#: the multiplier of the row hash (2^64 / golden ratio, odd)
_MIX = np.uint64(0x9E3779B97F4A7C15)


def merge_corners(table: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Merge equal rows (corners with the same position, normal and UV), bit for bit.

    Rows are grouped by a hash of their bits, sorted, and split wherever two neighbours differ in
    any bit, so a hash collision can only leave two equal rows apart, never merge different ones.
    About 6x faster than `np.unique(axis=0)` on a million triangles (docs/blender.md, Export).

    Args:
        table: N x C float32 rows.
    Returns:
        (unique, inverse): the distinct rows in order of first appearance (float32), and for every
        row its index in `unique` (unique[inverse] == table).
    """
    rows = np.ascontiguousarray(table, dtype=np.float32)
    n, width = rows.shape
    if n == 0:
        return rows.copy(), np.zeros(0, np.int64)
    if width % 2:  # whole 64-bit words
        rows = np.concatenate([rows, np.zeros((n, 1), np.float32)], axis=1)
    words = rows.view(np.uint64)
    h = np.zeros(n, np.uint64)
    for j in range(words.shape[1]):
        h ^= words[:, j]
        h *= _MIX  # wraps modulo 2^64, as a hash should
        h ^= h >> np.uint64(29)
    order = np.argsort(h, kind="stable")
    ordered = words[order]
    new = np.empty(n, bool)
    new[0] = True
    np.any(ordered[1:] != ordered[:-1], axis=1, out=new[1:])
    group = np.cumsum(new) - 1
    first = order[new]  # each group's first row (the sort is stable)
    rank = np.empty(len(first), np.int64)
    rank[np.argsort(first, kind="stable")] = np.arange(len(first))
    inverse = np.empty(n, np.int64)
    inverse[order] = rank[group]
    return np.ascontiguousarray(rows[np.sort(first), :width]), inverse


def read(mesh, matrix: np.ndarray | None = None) -> list[Part]:
    """The parts of an evaluated `bpy.types.Mesh`, one per material slot.

    Args:
        mesh: the evaluated mesh (modifiers applied). matrix: 4x4 to world space (None: keep local).

    Returns:
        The `Part`s ([] for a mesh without triangles).
    """
    mesh.calc_loop_triangles()
    tris = mesh.loop_triangles
    if len(tris) == 0:
        return []
    corners = _get(tris, "loops", 3, np.int32)              # T x 3 corner (loop) indices
    slots = _get(tris, "material_index", 1, np.int32)
    corner_vert = _get(mesh.loops, "vertex_index", 1, np.int32)
    co = _get(mesh.vertices, "co", 3, np.float32)
    if hasattr(mesh, "corner_normals"):
        normals = _get(mesh.corner_normals, "vector", 3, np.float32)
    else:  # Blender before 4.1 (e.g. 3.4, where docs/blender_viewport.png was taken)
        mesh.calc_normals_split()
        normals = _get(mesh.loops, "normal", 3, np.float32)
    uv_layer = mesh.uv_layers.active
    uvs = _get(uv_layer.data, "uv", 2, np.float32) if uv_layer is not None else None
    if matrix is not None:
        m = np.asarray(matrix, dtype=np.float64)
        co = (co @ m[:3, :3].T + m[:3, 3]).astype(np.float32)
        # normals move with the inverse transpose (non-uniform scale), then are renormalised
        normals = normals @ np.linalg.inv(m[:3, :3])
        normals = (
            normals / np.maximum(np.linalg.norm(normals, axis=1, keepdims=True), 1e-20)
        ).astype(np.float32)
        if np.linalg.det(m[:3, :3]) < 0:  # a mirroring transform turns the winding round
            corners = corners[:, ::-1]
    parts = []
    for slot in np.unique(slots):
        c = corners[slots == slot].reshape(-1)
        cols = [co[corner_vert[c]], normals[c]]
        if uvs is not None:
            uv = uvs[c].copy()
            uv[:, 1] = units.flip_v(uv[:, 1])
            cols.append(uv)
        unique, inverse = merge_corners(np.concatenate(cols, axis=1))
        parts.append(Part(int(slot), unique[:, :3].copy(), unique[:, 3:6].copy(),
                          unique[:, 6:8].copy() if uvs is not None else None,
                          inverse.reshape(-1, 3).astype(np.uint32)))
    return parts


def to_mitsuba(part: Part, name: str, bsdf=None, emitter=None):
    """An `mi.Mesh` holding `part`, with its BSDF (and area emitter) objects attached.

    Args:
        part: the part. name: the mesh's name. bsdf: the BSDF object, or None.
        emitter: the area emitter object, or None.

    Returns:
        The mi.Mesh.
    """
    import mitsuba as mi
    props = mi.Properties()
    if bsdf is not None:
        props["bsdf"] = bsdf
    if emitter is not None:
        props["emitter"] = emitter
    mesh = mi.Mesh(name, len(part.positions), len(part.faces), props=props, has_vertex_normals=True,
                   has_vertex_texcoords=part.uvs is not None)
    place(mesh, part)
    return mesh


def fits(mesh, part: Part) -> bool:
    """Whether `part` can be written into `mesh` (`place`): as many vertices and faces, and
    texture coordinates on both or neither.

    Args:
        mesh: an `mi.Mesh` of `to_mitsuba`. part: the part.

    Returns:
        True where it fits.
    """
    return (mesh.vertex_count() == len(part.positions) and mesh.face_count() == len(part.faces)
            and mesh.has_vertex_texcoords() == (part.uvs is not None))


def place(mesh, part: Part) -> None:
    """Write `part`'s vertices and faces into `mesh` (one that `fits` it), as `to_mitsuba` does
    into a new one: the mesh keeps its BSDF and emitter objects, and so their Dr.Jit registry ids
    (a moved object's new objects would raise the registry's id bound, which Dr.Jit's code for
    method calls depends on: docs/design/viewport.md, "Object moves").

    Args:
        mesh: the `mi.Mesh`. part: the part.
    """
    import mitsuba as mi
    params = mi.traverse(mesh)
    params["vertex_positions"] = mi.Float(part.positions.reshape(-1))
    params["vertex_normals"] = mi.Float(part.normals.reshape(-1))
    if part.uvs is not None:
        params["vertex_texcoords"] = mi.Float(part.uvs.reshape(-1))
    params["faces"] = mi.UInt32(part.faces.reshape(-1))
    params.update()
