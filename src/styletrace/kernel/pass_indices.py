"""Blender's pass indices of a scene's shapes (the Object Index and Material Index passes): each
shape's object and material pass index, carried in the shape's id, so that a scene dict, a scene
built in Python and an XML file carry them alike (Mitsuba refuses properties it does not know).

    shape_id("shape_3", 7, 5)             # 'shape_3__ob7__ma5' (Blender's exporter's ids)
    indices_of("shape_3__ob7__ma5")       # (7, 5); an id without them: (0, 0)
    table = IndexTable.of(scene)          # every shape's, by the registry id a hit reports
    ob, ma = table.lookup(si, valid)      # per lane, mi.Float (0 where nothing is hit)

Docs: docs/scenes.md (Pass indices).
"""
from __future__ import annotations

import re

import numpy as np

from styletrace.gate import dr, mi
from styletrace.kernel.shape_tables import gather_columns, rows_by_shape, table_of

#: the object index's and the material index's marks at the end of a shape's id
INDEX = re.compile(r"__ob(\d+)(?:__ma(\d+))?$|__ma(\d+)$")


def shape_id(base: str, object_index: int, material_index: int) -> str:
    """The id of a shape with these pass indices (`base` unchanged where both are 0).

    Args:
        base: the id without them ('shape_3'). object_index, material_index: Blender's
            `object.pass_index` and `material.pass_index` (>= 0).

    Returns:
        The id: base, then '__ob<k>' where the object's is not 0 and '__ma<m>' where the
        material's is not 0.
    """
    tail = f"__ob{int(object_index)}" if object_index else ""
    return base + tail + (f"__ma{int(material_index)}" if material_index else "")


def indices_of(ident: str) -> tuple[int, int]:
    """The pass indices an id carries (`shape_id`'s marks).

    Args:
        ident: a shape's id ('' for none).

    Returns:
        (object index, material index), 0 for each mark absent.
    """
    m = INDEX.search(ident or "")
    if m is None:
        return 0, 0
    ob, ma, ma_alone = m.groups()
    return int(ob or 0), int(ma or ma_alone or 0)


class IndexTable:
    """The pass indices of a loaded scene's shapes, by the registry id of `si.shape`.

    Args:
        values: (N + 1) x 2 float32: row k the (object, material) index of the shape whose
            registry id is k (0 for ids of no shape), or None where no shape carries any.
    """

    def __init__(self, values: np.ndarray | None):
        self.values = values

    @classmethod
    def of(cls, scene) -> "IndexTable":
        """The table of every shape with a surface (those inside shapegroups too).

        Args:
            scene: the loaded mi.Scene.

        Returns:
            The IndexTable.
        """
        rows = rows_by_shape(scene, lambda s: indices_of(s.id()))
        rows = {k: v for k, v in rows.items() if v != (0, 0)}
        return cls(table_of(rows, np.float32) if rows else None)

    def lookup(self, si, valid) -> tuple:
        """Each lane's (object index, material index).

        Args:
            si: the hits (mi.SurfaceInteraction3f). valid: mi.Bool, the lanes that hit.

        Returns:
            Two mi.Float: the hit shape's indices, 0 where `valid` is false or the shape carries
            none.
        """
        if self.values is None:
            n = dr.width(valid)
            return dr.zeros(mi.Float, n), dr.zeros(mi.Float, n)
        return gather_columns(self.values, mi.Float, si, valid)


__all__ = ["INDEX", "shape_id", "indices_of", "IndexTable"]
