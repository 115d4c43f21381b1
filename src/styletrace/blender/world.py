"""The Blender world -> a Mitsuba environment emitter.

A Background node gives a `constant` emitter of colour x strength; an Environment Texture behind it
an `envmap` of the image scaled by the strength. Cycles reads its equirectangular map (+Z up, the
image's centre column looking along +X) at u = 1/2 - atan2(d_y, d_x) / 2 pi, v = 1/2 + asin(d_z) /
pi; Mitsuba's envmap at u = atan2(l_x, -l_z) / 2 pi, v = acos(l_y) / pi (v from the top row) in its
local frame l. Equal u and v need l = (d_y, d_z, d_x), so to_world (d = M l) is the rotation
ENV_TO_WORLD (checked against Cycles: tests/blender/test_cycles.py, the textured plane's sky
and lighting).
"""
from __future__ import annotations

import numpy as np

from styletrace.blender.materials import MaterialContext, image_array

ENV_TO_WORLD = np.array(
    [[0.0, 0.0, 1.0, 0.0], [1.0, 0.0, 0.0, 0.0], [0.0, 1.0, 0.0, 0.0], [0.0, 0.0, 0.0, 1.0]]
)


def latitudes(rows: np.ndarray) -> np.ndarray:
    """The map's rows resampled for Mitsuba, so that its linear interpolation gives Cycles' curve.

    Cycles puts row i (of h, top first) at v = (i + 1/2) / h and interpolates linearly between rows;
    Mitsuba's envmap puts row k (of h') at v = k / (h' - 1). Rows at v = j / 2h, j = 0 .. 2h (the
    rows themselves and the midpoints between them, the poles clamped) match it exactly.

    Args:
        rows: the equirectangular image, H x W x C, top row first.

    Returns:
        2H + 1 rows, float32.
    """
    h = rows.shape[0]
    out = np.empty((2 * h + 1, *rows.shape[1:]), dtype=np.float32)
    out[1::2] = rows
    out[2:-1:2] = (rows[:-1] + rows[1:]) / 2
    out[0], out[-1] = rows[0], rows[-1]
    return out


def convert_world(world, ctx: MaterialContext) -> dict | None:
    """The environment emitter of the Blender world (see the module doc).

    Args:
        world: the `bpy.types.World`, or None. ctx: the export's MaterialContext (images, and the
            unsupported nodes it reports).

    Returns:
        A `constant` or `envmap` description, or None: no world, a black one, or an unsupported
        node (reported).
    """
    if world is None:
        return None
    tree = world.node_tree
    out = None
    if tree is not None:
        outs = [n for n in tree.nodes if n.bl_idname == "ShaderNodeOutputWorld"]
        out = next((n for n in outs if n.is_active_output), outs[0] if outs else None)
    if out is None or not out.inputs["Surface"].is_linked:
        c = tuple(float(v) for v in world.color)
        return {"type": "constant", "radiance": {"type": "rgb", "value": c}} if any(c) else None
    node = out.inputs["Surface"].links[0].from_node
    if node.bl_idname != "ShaderNodeBackground":
        ctx.unsupported.setdefault(node.bl_idname, []).append(f"world {world.name}")
        return None
    strength = float(node.inputs["Strength"].default_value)
    col = node.inputs["Color"]
    if col.is_linked:
        src = col.links[0].from_node
        if src.bl_idname == "ShaderNodeTexEnvironment" and src.image is not None:
            return {
                "type": "envmap",
                "data": latitudes(image_array(src.image, ctx)),
                "scale": strength,
                "to_world": ENV_TO_WORLD,
            }
        ctx.unsupported.setdefault(src.bl_idname, []).append(f"world {world.name}")
        return None
    c = tuple(float(v) * strength for v in col.default_value[:3])
    return {"type": "constant", "radiance": {"type": "rgb", "value": c}} if any(c) else None
