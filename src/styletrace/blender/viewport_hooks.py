"""Blender's side of Rendered shading: the engine's `view_update` and `view_draw`, drawing the
newest image of a view's session (`viewport.Viewport`, the model) and freeing views.

    view_update(engine, context, depsgraph)    # RenderEngine.view_update: sync the edits
    view_draw(engine, context, depsgraph)      # RenderEngine.view_draw: draw the newest image

Blender's UI is not touched from the worker: a timer (`REDRAW_S`) asks for a redraw where a
session has a newer image. Design: docs/design/viewport.md.
"""
from __future__ import annotations

import traceback

import numpy as np

from styletrace.blender.viewport import Viewport
from styletrace.errors import StyletraceError

#: the viewports of the live engines, by `RenderEngine.as_pointer()`
VIEWS: dict[int, Viewport] = {}
#: seconds between the main thread's checks for a new image (Blender's UI is not touched from the
#: worker: a timer asks for the redraw)
REDRAW_S = 0.05


def view_update(engine, context, depsgraph) -> None:
    """`RenderEngine.view_update`: sync the depsgraph's updates into this engine's viewport.

    Args:
        engine: the `RenderEngine`; its pointer keys `VIEWS`, its status line shows a refusal.
        context: Blender's context (unused).
        depsgraph: the evaluated depsgraph; its scene's styletrace settings are read.

    A refusal or a bug closes the viewport and shows one line in the status (not raised).
    """
    key = engine.as_pointer()
    vp = VIEWS.get(key)
    if vp is None:
        vp = VIEWS[key] = Viewport(warn=lambda m: print(m))
        vp.engine, vp.drawn = engine, -1
        import bpy
        bpy.app.timers.register(lambda: _poll(key), first_interval=REDRAW_S)
    try:
        vp.update(depsgraph, depsgraph.scene.styletrace)
    except StyletraceError as exc:
        vp.close()
        engine.update_stats("", f"styletrace: {str(exc).strip().splitlines()[0]}")
    # Mitsuba's refusal of the exported scene, or a bug: one line, the trace on stderr
    except Exception as exc:
        traceback.print_exc()
        vp.close()
        engine.update_stats("", f"styletrace: {type(exc).__name__}: {exc}".splitlines()[0])


def _poll(key: int) -> float | None:
    """Ask for a redraw where the session has a newer image; None ends the timer."""
    vp = VIEWS.get(key)
    if vp is None:
        return None
    s = vp.session
    if s is not None and (s.version != vp.drawn or s.error):
        try:
            vp.engine.tag_redraw()
        except ReferenceError:  # the engine was freed (the view left Rendered mode)
            free_key(key)
            return None
    return REDRAW_S


def view_draw(engine, context, depsgraph) -> None:
    """`RenderEngine.view_draw`: follow the region's camera; draw the newest image.

    Args:
        engine: the `RenderEngine` (its viewport in `VIEWS`; none: nothing is drawn).
        context: Blender's context: its `region` and `region_data` give the view and size.
        depsgraph: the evaluated depsgraph; its scene's colour management applies.
    """
    vp = VIEWS.get(engine.as_pointer())
    if vp is None:
        return
    region, rv3d = context.region, context.region_data
    vp.set_view(rv3d.view_matrix, rv3d.window_matrix, region.width, region.height)
    s = vp.session
    if s is None:
        return
    image, label = s.latest()
    engine.update_stats("", f"styletrace: {s.error or label or 'starting'}")
    if image is None:
        return
    vp.drawn = s.version
    draw_view_image(engine, depsgraph.scene, image, region.width, region.height)


#: Blender shifts a region's pixel space by 0.01 px (GLA_PIXEL_OFS); a texture drawn at
#: (-PIXEL_OFFSET, -PIXEL_OFFSET) lands on the pixel centres, unblurred
#: (tests/blender/test_viewport_draw.py)
PIXEL_OFFSET = 0.01


def draw_view_image(engine, scene, image: np.ndarray, width: int, height: int) -> None:
    """Draw `image` over the region, through the view's colour management
    (`bind_display_space_shader`).

    Args:
        engine: the `RenderEngine` whose display-space shader is bound.
        scene: the Blender scene whose view transform, look and exposure apply.
        image: H x W x 3 floats, linear, top row first; stretched to the region.
        width, height: the region's size in pixels.
    """
    import gpu
    from gpu_extras.presets import draw_texture_2d
    texture = view_texture(image)
    gpu.state.blend_set("ALPHA_PREMULT")
    engine.bind_display_space_shader(scene)
    draw_texture_2d(texture, (-PIXEL_OFFSET, -PIXEL_OFFSET), width, height)
    engine.unbind_display_space_shader()
    gpu.state.blend_set("NONE")


def view_texture(image: np.ndarray):
    """`image` as the texture `draw_view_image` draws: opaque RGBA half floats, bottom row first.

    Args:
        image: H x W x 3 floats, linear, top row first.

    Returns:
        gpu.types.GPUTexture of W x H.
    """
    import gpu
    h, w = image.shape[:2]
    px = np.ones((h, w, 4), np.float32)
    px[..., :3] = image[::-1]
    data = gpu.types.Buffer("FLOAT", w * h * 4, px.reshape(-1))
    return gpu.types.GPUTexture((w, h), format="RGBA16F", data=data)


def free_key(key: int) -> None:
    """Forget the viewport of an engine and stop its session.

    Args:
        key: the engine's `as_pointer()`; a key with no viewport is ignored.
    """
    vp = VIEWS.pop(key, None)
    if vp is not None:
        vp.close()


def free_all(*_args) -> None:
    """Stop and forget every viewport: a `load_pre` handler, since Blender drops the engines of
    the old file without their `__del__` reaching `free`.

    Args:
        _args: what Blender passes a handler (the file path, ...), unused.
    """
    for key in list(VIEWS):
        free_key(key)


def register_viewport_hooks() -> None:
    """Free the viewports whenever Blender loads a file (`free_all`)."""
    import bpy
    # persistent: Blender keeps the handler across the loads it is there for
    bpy.app.handlers.persistent(free_all)
    if free_all not in bpy.app.handlers.load_pre:
        bpy.app.handlers.load_pre.append(free_all)


def unregister_viewport_hooks() -> None:
    """Remove the load handler and free every viewport."""
    import bpy
    if free_all in bpy.app.handlers.load_pre:
        bpy.app.handlers.load_pre.remove(free_all)
    free_all()


def free(engine) -> None:
    """The engine is going away (`RenderEngine.__del__`): stop its session.

    Args:
        engine: the `RenderEngine`; one already freed by Blender (ReferenceError) is ignored.
    """
    try:
        free_key(engine.as_pointer())
    except ReferenceError:
        pass


__all__ = ["VIEWS", "REDRAW_S", "PIXEL_OFFSET", "view_update", "view_draw", "draw_view_image",
           "view_texture",
           "free_key", "free_all", "free", "register_viewport_hooks", "unregister_viewport_hooks"]
