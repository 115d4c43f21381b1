"""Per-shape tables a kernel reads by the shape a hit reports: a row per registry id of `si.shape`
(the pass indices of `pass_indices`, the Cryptomatte ids of `asset_names`).

    rows = rows_by_shape(scene, lambda s: indices_of(s.id()))   # {registry id: row}
    table = table_of(rows, np.float32)                           # (N + 1) x C, 0 elsewhere
    ob, ma = gather_columns(table, mi.Float, si, valid)          # per lane, 0 where not valid
"""
from __future__ import annotations

from typing import Any, Callable

import numpy as np

from styletrace.gate import dr, mi
from styletrace.host_arrays import aligned


def shape_registry_id(shape) -> int:
    """The registry id a hit on `shape` reports in `si.shape` (an instanced shape's own, not its
    instance's).

    Args:
        shape: an mi.Shape.

    Returns:
        The id, an int.
    """
    return int(dr.reinterpret_array(mi.UInt32, mi.ShapePtr(shape))[0])


def rows_by_shape(scene, row: Callable[[Any], Any]) -> dict[int, Any]:
    """`row` of every shape with a surface (those inside shapegroups too), by registry id.

    Args:
        scene: the loaded mi.Scene. row: a shape's row.

    Returns:
        {registry id: row}.
    """
    from styletrace.kernel.scene_graph import all_shapes
    return {shape_registry_id(s): row(s) for s in all_shapes(scene)}


def table_of(rows: dict[int, Any], dtype) -> np.ndarray:
    """The rows as an array indexed by registry id, zeros for ids of no row.

    Args:
        rows: {registry id: a row of equal length}. dtype: the array's element type.

    Returns:
        (max id + 1) x the rows' length (at least 1 x 2 with no rows).
    """
    width = len(next(iter(rows.values()))) if rows else 2
    table = np.zeros((max(rows, default=0) + 1, width), dtype)
    for k, v in rows.items():
        table[k] = v
    return table


def gather_columns(table: np.ndarray, array_type, si, valid) -> tuple:
    """Each lane's row of the hit shape, a column each.

    Args:
        table: `table_of`'s array. array_type: mi.Float or mi.UInt32 (the table's type).
        si: the hits (mi.SurfaceInteraction3f). valid: mi.Bool, the lanes that hit.

    Returns:
        One `array_type` per column, 0 where `valid` is false or the id is past the table.
    """
    key = dr.reinterpret_array(mi.UInt32, si.shape)
    inside = valid & (key < len(table))
    # the columns as opaque, 64-byte aligned arrays: another scene's table reuses the compiled
    # kernel, whatever numpy's allocator gave (host_arrays)
    return tuple(dr.gather(array_type, array_type(aligned(table[:, c], table.dtype)), key, inside)
                 for c in range(table.shape[1]))


__all__ = ["shape_registry_id", "rows_by_shape", "table_of", "gather_columns"]
