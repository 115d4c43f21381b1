"""The object and material names of a scene's shapes (the Cryptomatte passes): carried in the
shape's id as the pass indices are (`kernel.pass_indices`), since Mitsuba refuses properties it
does not know and a name may hold any character (Blender's 'Cube.001').

    named_id("shape_3", "Cube.001", "Red")   # 'shape_3__cm437562652e303031_526564'
    names_in("shape_3__cm437562652e303031_526564__ob7")   # ('Cube.001', 'Red')
    table = NameTable.of(scene)              # every shape's ids, by the registry id a hit reports
    ob, ma = table.lookup(si, valid)         # per lane, mi.UInt32: the ids' float32 bits, 0: none
    table.manifests                          # {'CryptoObject': {name: hex}, 'CryptoMaterial': ...}

A shape whose id carries no names (a plain XML or Python scene) is named by its id without the
index marks, and its material by its BSDF's id. An id-less shape takes its BSDF's id as its name
too (Mitsuba merges the meshes that share a BSDF into one id-less mesh: nothing else tells them
apart), 'shape' where the BSDF has none either; a BSDF without an id takes the shape's name.
Docs: docs/scenes.md (Names), docs/passes.md (Cryptomatte).
"""
from __future__ import annotations

import re

import numpy as np

from styletrace.cryptomatte import id_bits, manifest
from styletrace.gate import mi
from styletrace.kernel.pass_indices import INDEX
from styletrace.kernel.shape_tables import gather_columns, rows_by_shape, table_of

#: the names' mark in a shape's id: '__cm', the object's name, '_', the material's, each as the
#: lower-case hex digits of its UTF-8 bytes (an id keeps letters, digits and underscores only)
NAMES = re.compile(r"__cm([0-9a-f]*)_([0-9a-f]*)(?=__ob|__ma|$)")
#: the Cryptomatte types, as Cycles names its passes
OBJECT, MATERIAL = "CryptoObject", "CryptoMaterial"


def named_id(base: str, object_name: str, material_name: str) -> str:
    """The id of a shape of this object and material (the pass indices' marks go after it).

    Args:
        base: the id without them ('shape_3'). object_name, material_name: Blender's names.

    Returns:
        base + '__cm' + the object's name in hex + '_' + the material's in hex.
    """
    return f"{base}__cm{object_name.encode('utf-8').hex()}_{material_name.encode('utf-8').hex()}"


def names_in(ident: str) -> tuple[str, str] | None:
    """The names an id carries (`named_id`'s mark).

    Args:
        ident: a shape's id.

    Returns:
        (object name, material name), or None where the id carries no mark (or a mark whose
        bytes are not UTF-8).
    """
    m = NAMES.search(ident or "")
    if m is None or len(m.group(1)) % 2 or len(m.group(2)) % 2:
        return None
    try:
        return tuple(bytes.fromhex(g).decode("utf-8") for g in m.groups())
    except UnicodeDecodeError:
        return None


def names_of(shape) -> tuple[str, str]:
    """A shape's object and material names (the module doc's rule).

    Args:
        shape: an mi.Shape.

    Returns:
        (object name, material name).
    """
    ident = shape.id()
    found = names_in(ident)
    if found is not None:
        return found
    bsdf = shape.bsdf()
    material = bsdf.id() if bsdf is not None else ""
    own = INDEX.sub("", ident) or material or "shape"
    return own, material or own


class NameTable:
    """The Cryptomatte ids of a loaded scene's shapes, by the registry id of `si.shape`.

    Args:
        bits: (N + 1) x 2 uint32: row k the float32 bits of the object's and the material's id of
            the shape whose registry id is k (0 for ids of no shape).
        manifests: {OBJECT: manifest, MATERIAL: manifest} of the names (`cryptomatte.manifest`).
    """

    def __init__(self, bits: np.ndarray, manifests: dict[str, dict[str, str]]):
        self.bits, self.manifests = bits, manifests

    @classmethod
    def of(cls, scene) -> "NameTable":
        """The table of every shape with a surface (those inside shapegroups too).

        Args:
            scene: the loaded mi.Scene.

        Returns:
            The NameTable.
        """
        rows = rows_by_shape(scene, names_of)
        bits = table_of({k: (id_bits(ob), id_bits(ma)) for k, (ob, ma) in rows.items()},
                        np.uint32)
        return cls(bits, {OBJECT: manifest(ob for ob, _ in rows.values()),
                          MATERIAL: manifest(ma for _, ma in rows.values())})

    def lookup(self, si, valid) -> tuple:
        """Each lane's object and material id.

        Args:
            si: the hits (mi.SurfaceInteraction3f). valid: mi.Bool, the lanes that hit.

        Returns:
            Two mi.UInt32: the float32 bits of the hit shape's ids, 0 where `valid` is false.
        """
        return gather_columns(self.bits, mi.UInt32, si, valid)


__all__ = ["NAMES", "OBJECT", "MATERIAL", "named_id", "names_in", "names_of", "NameTable"]
