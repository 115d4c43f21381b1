"""styletrace in Blender: a render engine, style panels generated from the registries, an
in-process exporter from the evaluated depsgraph to a Mitsuba scene, restyling from a recorded
buffer, and File -> Export -> Mitsuba XML. See docs/blender.md.

    import bpy, styletrace.blender
    styletrace.blender.register()
    bpy.context.scene.render.engine = "STYLETRACE"

Modules: `mesh`, `camera`, `lights`, `world`, `materials` convert one kind of datablock each
(`units`: the light units); `exporter` walks the depsgraph; `build` makes the Mitsuba objects,
`xml` the file; `properties`, `panels` the UI; `engine`, `f12` render; `restyle`, `operators`,
`extension`. Design: docs/design/blender_export.md.
"""
from __future__ import annotations

bl_info = {"name": "styletrace", "author": "styletrace", "version": (0, 1, 0), "blender": (4, 2, 0),
           "location": "Render Properties > Render Engine > styletrace", "category": "Render",
           "description": "Stylized global illumination as a function of expectation (Mitsuba 3)"}

_MODULES = ("properties", "engine", "panels", "restyle", "operators", "viewport_hooks")


def _modules():
    from importlib import import_module
    return [import_module(f".{name}", __name__) for name in _MODULES]


def register():
    for name, module in zip(_MODULES, _modules()):
        getattr(module, f"register_{name}")()


def unregister():
    for name, module in reversed(list(zip(_MODULES, _modules()))):
        getattr(module, f"unregister_{name}")()
