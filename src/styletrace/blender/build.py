"""A scene description (`exporter`) -> a Mitsuba scene dict with objects made in process: meshes
become `mi.Mesh`es filled from numpy, images `mi.Bitmap`s, matrices `mi.ScalarTransform4f`s. No file
is written."""
from __future__ import annotations

from typing import Any

import numpy as np


def _value(value: Any) -> Any:
    import mitsuba as mi
    if isinstance(value, np.ndarray) and value.shape == (4, 4):
        return mi.ScalarTransform4f(value.tolist())
    if isinstance(value, dict):
        return node(value)
    return value


def node(d: dict) -> Any:
    """One description node as what `mi.load_dict` accepts: a dict, or an object made here.

    Args:
        d: a description node. A "blender_mesh" becomes an `mi.Mesh` with its BSDF and emitter,
            "data" a `mi.Bitmap` (as "bitmap"), a 4x4 array a `mi.ScalarTransform4f`; nested
            nodes likewise.

    Returns:
        The dict, or the mesh.
    """
    import mitsuba as mi

    from styletrace.blender.mesh import to_mitsuba
    kind = d.get("type")
    if kind == "blender_mesh":
        bsdf = mi.load_dict(node(d["bsdf"]))
        emitter = mi.load_dict(node(d["emitter"])) if "emitter" in d else None
        return to_mitsuba(d["part"], d["name"], bsdf, emitter)
    out = {}
    for key, value in d.items():
        if key == "data":
            out["bitmap"] = mi.Bitmap(np.ascontiguousarray(value, dtype=np.float32))
        else:
            out[key] = _value(value)
    return out


def description_scene_dict(desc: dict) -> dict:
    """The Mitsuba scene dict of a description, for `styletrace.frontends.api.load_scene` or
    `mi.load_dict`.

    Args:
        desc: the scene description (`exporter.export`).

    Returns:
        The scene dict, its meshes, images and matrices made in process.
    """
    return node(desc)
