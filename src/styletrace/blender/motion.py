"""The Vector pass's motion in Blender: the camera and the objects one frame before and one frame
after the frame rendered, as Cycles takes them, for the exported scene
(`kernel.data_passes.Motion`).

    placements = {}
    desc = f12.description(depsgraph, settings, warn, placements)  # each shape's placement
    motion = frames_around(engine, depsgraph, f12.load(desc), placements)

The depsgraph is evaluated at frame - 1 and frame + 1 with the engine's `frame_set` (Cycles' way;
it works in F12, Render Animation and bpy as a module), then at the frame again. Objects move
rigidly: a shape's points are mapped by M_then @ inverse(M_now) of its object or instance
placement, so a deforming mesh's own motion (an armature, shape keys, a simulation) is not
followed, nor is an instance that exists in one frame only. Docs: docs/passes.md.
"""
from __future__ import annotations

import numpy as np

from styletrace.blender import build, camera
from styletrace.blender.exporter import placement_key
from styletrace.kernel.data_passes import Motion, View

#: the object types the exporter turns into meshes (`exporter.Exporter.export`)
MESHES = ("MESH", "CURVE", "SURFACE", "META", "FONT")


def placements(depsgraph) -> dict[tuple, np.ndarray]:
    """Where every drawn mesh object and instance sits in the depsgraph's current frame.

    Args:
        depsgraph: the evaluated depsgraph.

    Returns:
        {placement key (`exporter.placement_key`): its 4x4 matrix_world}.
    """
    out = {}
    for inst in depsgraph.object_instances:
        if inst.show_self and inst.object.type in MESHES:
            out[placement_key(inst)] = np.array(inst.matrix_world, dtype=np.float64)
    return out


def view(depsgraph) -> View:
    """The scene camera's view in the depsgraph's current frame (its lens and placement there).

    Args:
        depsgraph: the evaluated depsgraph.

    Returns:
        The `kernel.data_passes.View` of the sensor the exporter makes of it.
    """
    import mitsuba as mi
    desc = camera.sensor(depsgraph.scene_eval, 1, warn=lambda _: None)
    desc.pop("sampler")  # the view needs the lens and the film only
    return View.of(mi.load_dict(build.node(desc)))


def deltas(now: dict, before: dict, after: dict, key: tuple) -> tuple | None:
    """The maps of one placement's points to the previous and the next frame, where it moves.

    Args:
        now, before, after: `placements` of the three frames. key: the placement.

    Returns:
        (to previous, to next), 4x4 each (identity in a frame where the placement is missing);
        None where it does not move or is not placed now.
    """
    if key not in now:
        return None
    here = now[key]
    if all(key not in then or np.array_equal(then[key], here) for then in (before, after)):
        return None  # most objects stand still: no inverse for them
    inverse = np.linalg.inv(here)
    return tuple(then[key] @ inverse if key in then else np.eye(4) for then in (before, after))


def frames_around(engine, depsgraph, scene, keys: dict[str, tuple]) -> Motion:
    """The motion of the frames either side of the one rendered; the depsgraph is put back at its
    frame (and subframe) afterwards, whatever happens.

    Args:
        engine: the `bpy.types.RenderEngine` rendering (its `frame_set`).
        depsgraph: the render's evaluated depsgraph, at the frame rendered.
        scene: the mi.Scene exported from it. keys: {shape id in the scene: placement key}
            (`exporter.export`'s placements).

    Returns:
        The `kernel.data_passes.Motion`: the camera's views, and the shapes that move.
    """
    frame, subframe = depsgraph.scene.frame_current, depsgraph.scene.frame_subframe
    now = placements(depsgraph)
    around = []
    try:
        for other in (frame - 1, frame + 1):
            engine.frame_set(other, subframe)
            around.append((view(depsgraph), placements(depsgraph)))
    finally:
        engine.frame_set(frame, subframe)
    (before_view, before), (after_view, after) = around
    shapes = []
    for shape in scene.shapes():
        key = keys.get(shape.id())
        maps = deltas(now, before, after, key) if key is not None else None
        if maps is not None:
            shapes.append((shape, *maps))
    return Motion(before_view, after_view, tuple(shapes))


__all__ = ["MESHES", "placements", "view", "deltas", "frames_around"]
