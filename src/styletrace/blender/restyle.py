"""Restyle inside Blender: the last render's look-development buffer, re-evaluated when a style
setting changes.

With "Record buffer" on, F12 records the buffer (`styletrace.lookdev`: per camera sample, everything
the image depends on except the style's parameters). A later change of the render style or its
parameters restyles the buffer (milliseconds for small images) into the image datablock `IMAGE`,
which an Image Editor shows. A refused value is a one-line error report of the `styletrace.restyle`
operator; a change made through a property's update callback prints that line and keeps the
previous image.
"""
from __future__ import annotations

import time

import bpy
import numpy as np

from styletrace.blender.properties import ON_CHANGE, style_values
from styletrace.errors import StyletraceError

IMAGE = "styletrace restyle"

_state: dict = {"buffer": None, "seconds": None, "error": ""}


def forget():
    _state["buffer"] = None


def keep(buf):
    """Keep `buf` for restyles (F12 with Record buffer: its recorded buffer, the denoised one with
    Denoise 'expectation').

    Args:
        buf: the buffer.
    """
    _state["buffer"] = buf


def buffer():
    return _state["buffer"]


def last_seconds():
    return _state["seconds"]


def restyle_recorded(settings) -> np.ndarray:
    """Restyle the recorded buffer with the render settings' style into the image datablock `IMAGE`.

    Args:
        settings: the scene's styletrace settings.

    Returns:
        The image, H x W x 3.

    Raises:
        StyletraceError: no recorded buffer, or a refused value (one line).
    """
    from styletrace.lookdev.restyle import restyle as lookdev_restyle
    buf = _state["buffer"]
    if buf is None:
        raise StyletraceError("no recorded buffer: turn on Record buffer and render (F12) first")
    values = style_values(settings)
    style = values.pop("style")
    inner = values.pop("inner_samples", None)
    estimator = values.pop("estimator", None)
    start = time.perf_counter()
    img = lookdev_restyle(buf, style=style, inner=inner, estimator=estimator, **values)
    _state["seconds"] = time.perf_counter() - start
    _write(img)
    return img


def _write(img: np.ndarray) -> None:
    h, w = img.shape[:2]
    image = bpy.data.images.get(IMAGE)
    if image is None or tuple(image.size) != (w, h):
        if image is not None:
            bpy.data.images.remove(image)
        image = bpy.data.images.new(IMAGE, w, h, alpha=True, float_buffer=True)
    px = np.ones((h, w, 4), np.float32)
    px[..., :3] = img[::-1]
    image.pixels.foreach_set(px.reshape(-1))
    image.update()


def on_change(context) -> None:
    """A style setting changed: restyle if a buffer is kept; a refusal is printed as one line and
    the previous image kept (the operator reports errors).

    Args:
        context: Blender's context.
    """
    scene = getattr(context, "scene", None)
    if _state["buffer"] is None or scene is None or not scene.styletrace.record_buffer:
        return
    try:
        restyle_recorded(scene.styletrace)
        _state["error"] = ""
    except StyletraceError as exc:
        _state["error"] = str(exc).splitlines()[0]
        print(f"styletrace: {_state['error']}")


class STYLETRACE_OT_restyle(bpy.types.Operator):
    """Restyle the recorded buffer of the last render with the current style settings"""

    bl_idname = "styletrace.restyle"
    bl_label = "Restyle"

    def execute(self, context):
        try:
            restyle_recorded(context.scene.styletrace)
        except StyletraceError as exc:
            self.report({"ERROR"}, str(exc).splitlines()[0])
            return {"CANCELLED"}
        self.report({"INFO"}, f"restyled in {_state['seconds'] * 1000:.0f} ms")
        return {"FINISHED"}


def register_restyle():
    bpy.utils.register_class(STYLETRACE_OT_restyle)
    ON_CHANGE.append(on_change)


def unregister_restyle():
    ON_CHANGE.remove(on_change)
    bpy.utils.unregister_class(STYLETRACE_OT_restyle)
    forget()
