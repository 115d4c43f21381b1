"""Remake docs/blender_panel.png: a screenshot of Blender's GUI with styletrace's panels
(docs/blender.md).

Run by Blender itself (a GUI, not `bpy` as a module, which draws nothing), e.g. Debian's Blender 3.4
under Xvfb:

    STYLETRACE_SITE=/path/to/.venv/lib/python3.11/site-packages \\
    xvfb-run -a -s "-screen 0 1600x1000x24" blender --factory-startup \\
        --python docs/make_blender_screenshot.py

STYLETRACE_SITE defaults to the repository's .venv; Blender's Python must be its minor version (3.11
for Debian bookworm's Blender). Only styletrace's dependencies (mitsuba, drjit, numpy, tqdm) and PIL
are taken from it, through a folder of links, so nothing else of the venv (e.g. its `bpy` wheel)
shadows Blender's own modules.

The script registers `styletrace.blender`, sets the render engine to styletrace, splits the 3D
viewport into two Properties editors (Render with the `hatching` style, Material with a per-material
`color_map` style), takes Blender's own screenshot of the window (`screen.screenshot`), crops it to
the two editors with numpy + PIL and quits. STYLETRACE_SHOT_FULL=PATH also keeps the uncropped
window.
"""
import os
import shutil
import sys
from importlib import import_module

import bpy

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)
OUT = os.environ.get("STYLETRACE_SHOT", os.path.join(HERE, "blender_panel.png"))

sys.path.insert(0, os.path.join(ROOT, "src"))
site = import_module("styletrace.blender.borrowed_site")
links = site.borrow_site(ROOT, site.PACKAGES)  # no denoiser: F12 is not run here

# styletrace and its dependencies are importable only now: loaded by name
blender = import_module("styletrace.blender")
blender.register()
scene = bpy.context.scene
scene.render.engine = "STYLETRACE"
scene.styletrace.style = "hatching"
material = bpy.data.objects["Cube"].active_material
material.styletrace.use_style = True
material.styletrace.style = "color_map"

bpy.context.preferences.view.show_splash = False
window = bpy.context.window_manager.windows[0]
view3d = next(a for a in window.screen.areas if a.type == "VIEW_3D")
with bpy.context.temp_override(window=window, screen=window.screen, area=view3d):
    bpy.ops.screen.area_split(direction="VERTICAL", factor=0.6)
render_area, material_area = sorted(
    (a for a in window.screen.areas if a.type == "VIEW_3D"), key=lambda a: a.x
)
for area in (render_area, material_area):
    area.type = "PROPERTIES"


def tabs():
    """The Properties editors' tabs, once they have been drawn (before, their tab list is empty)."""
    for area, tab in ((render_area, "RENDER"), (material_area, "MATERIAL")):
        area.spaces.active.context = tab
        area.tag_redraw()
    outliner = next(a for a in window.screen.areas if a.type == "OUTLINER")
    # no tooltip over the panels
    window.cursor_warp(outliner.x + outliner.width // 2, outliner.y + 10)


def shoot():
    full = os.path.join(links, "window.png")
    with bpy.context.temp_override(window=window, screen=window.screen, area=render_area):
        bpy.ops.screen.screenshot(filepath=full)
    boxes = [(a.x, a.y, a.width, a.height) for a in (render_area, material_area)]
    if os.environ.get("STYLETRACE_SHOT_FULL"):
        shutil.copy(full, os.environ["STYLETRACE_SHOT_FULL"])
    print(
        "styletrace screenshot:",
        bpy.app.version_string,
        "window",
        window.width,
        window.height,
        "areas",
        boxes,
    )
    try:
        import numpy as np
        from PIL import Image
    except ImportError:
        os.replace(full, OUT)
    else:
        img = np.asarray(Image.open(full))
        h = img.shape[0]
        x0 = min(b[0] for b in boxes)
        x1 = max(b[0] + b[2] for b in boxes)
        y_top = max(b[1] + b[3] for b in boxes)  # Blender's y runs up from the window's bottom
        y_bottom = min(b[1] for b in boxes)
        Image.fromarray(img[h - y_top:h - y_bottom, x0:x1]).save(OUT)
    print("styletrace screenshot written:", OUT)
    bpy.ops.wm.quit_blender()


bpy.app.timers.register(tabs, first_interval=1.0)
bpy.app.timers.register(shoot, first_interval=float(os.environ.get("STYLETRACE_SHOT_DELAY", "4")))
