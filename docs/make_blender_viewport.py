"""Remake docs/blender_viewport.png: Blender's 3D viewport in Rendered shading with styletrace's
engine and the cel style (docs/blender.md, Viewport).

Run by Blender itself (a GUI: `bpy` as a module draws nothing), e.g. Debian's Blender 3.4 under
Xvfb, as docs/make_blender_screenshot.py:

    LD_PRELOAD=/lib/x86_64-linux-gnu/libhwloc.so.15 \\
    STYLETRACE_SITE=/path/to/.venv/lib/python3.11/site-packages \\
    xvfb-run -a -s "-screen 0 760x490x24" blender --factory-startup \\
        --python docs/make_blender_viewport.py

(LD_PRELOAD: Debian's Blender allocates with jemalloc, and the system's hwloc, which the oneTBB
bundled with pyoidn calls, frees its memory with glibc's `free`: Blender aborts on the first
denoise; hwloc preloaded binds to jemalloc. docs/blender.md, Viewport.)

The script builds a small scene (the startup cube, a sphere and a torus on a floor, an area light
and a dim sky), sets the render engine to styletrace with the cel style and every other render
setting at its default (Denoise auto: expectation where the view's buffer fits its cap), switches
the 3D view to Rendered shading, waits for the last pass, then moves the cube and changes the cel
levels (printing the viewport's log: what each update re-exported and how long it took), waits
again, takes Blender's screenshot of the window, crops it to the 3D view and quits. Timings print
as `styletrace viewport:` lines, and whether the denoiser could be imported.
"""
import math
import os
import sys
import time
from importlib import import_module

import bpy
from mathutils import Quaternion, Vector

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)
OUT = os.environ.get("STYLETRACE_SHOT", os.path.join(HERE, "blender_viewport.png"))
TIMEOUT_S = float(os.environ.get("STYLETRACE_VIEWPORT_TIMEOUT", "300"))

sys.path.insert(0, os.path.join(ROOT, "src"))
links = import_module("styletrace.blender.borrowed_site").borrow_site(ROOT)  # with the denoiser

# styletrace comes from the links and src/ put on sys.path above: imported by name
addon = import_module("styletrace.blender")
viewport = import_module("styletrace.blender.viewport_hooks")
addon.register()
scene = bpy.context.scene
scene.render.engine = "STYLETRACE"
st = scene.styletrace
st.style = "cel"  # every other setting at its default: 16 spp in passes of 4, Denoise auto

cube = bpy.data.objects["Cube"]
cube.location = (0.0, 0.0, 1.0)
cube.rotation_euler = (0.0, 0.0, math.radians(20))
bpy.ops.mesh.primitive_plane_add(size=16, location=(0, 0, 0))
bpy.ops.mesh.primitive_uv_sphere_add(radius=0.9, location=(2.3, 1.0, 0.9), segments=48,
                                     ring_count=24)
bpy.ops.object.shade_smooth()
bpy.ops.mesh.primitive_torus_add(location=(-1.6, 1.9, 0.35), major_radius=0.9, minor_radius=0.35)
bpy.ops.object.shade_smooth()
for name, colour in (("Cube", (0.8, 0.25, 0.15)), ("Plane", (0.75, 0.75, 0.7)),
                     ("Sphere", (0.2, 0.45, 0.8)), ("Torus", (0.85, 0.7, 0.2))):
    mat = bpy.data.materials.new(name.lower())
    mat.use_nodes = True  # a Diffuse BSDF: 3.4's Principled has other socket names than 4.x's
    nt = mat.node_tree
    nt.nodes.remove(nt.nodes["Principled BSDF"])
    node = nt.nodes.new("ShaderNodeBsdfDiffuse")
    node.inputs["Color"].default_value = (*colour, 1.0)
    nt.links.new(node.outputs[0], nt.nodes["Material Output"].inputs["Surface"])
    obj = bpy.data.objects[name]
    obj.data.materials.clear()
    obj.data.materials.append(mat)
# an area light close above: its falloff spreads the floor over the bands, its shadows add edges
area = bpy.data.lights.new("area", "AREA")
area.energy, area.size = 2000.0, 2.0
area_obj = bpy.data.objects.new("area", area)
scene.collection.objects.link(area_obj)
area_obj.location = (2.0, -3.0, 6.5)  # above the view's top edge: an area light is seen
area_obj.rotation_euler = (Vector((0.0, 0.5, 0.0)) - area_obj.location).to_track_quat(
    "-Z", "Y").to_euler()
for name in ("Light",):  # the startup point light: the area light alone
    bpy.data.objects.remove(bpy.data.objects[name])
world = scene.world
world.use_nodes = True
world.node_tree.nodes["Background"].inputs["Color"].default_value = (0.5, 0.6, 0.8, 1.0)
world.node_tree.nodes["Background"].inputs["Strength"].default_value = 0.3

bpy.context.preferences.view.show_splash = False
window = bpy.context.window_manager.windows[0]
view3d = next(a for a in window.screen.areas if a.type == "VIEW_3D")
space = view3d.spaces.active
space.overlay.show_overlays = False
space.show_gizmo = False
rv3d = space.region_3d
rv3d.view_distance = 11.0
rv3d.view_rotation = Quaternion((0.82, 0.42, 0.18, 0.34)).normalized()
rv3d.view_location = (0.5, 0.3, 0.6)
space.shading.type = "RENDERED"
state = {"t0": time.perf_counter(), "step": "first", "seen": set()}


def say(*args):
    print("styletrace viewport:", *args, flush=True)


try:
    import pyoidn  # noqa: F401
    say("denoiser: pyoidn", pyoidn.__file__)
except ImportError as exc:
    say("denoiser unavailable:", exc)


def session():
    views = list(viewport.VIEWS.values())
    return views[0] if views else None


def step():
    vp = session()
    elapsed = time.perf_counter() - state["t0"]
    if elapsed > TIMEOUT_S:
        say("timed out in step", state["step"])
        bpy.ops.wm.quit_blender()
        return None
    s = vp.session if vp else None
    if s is None:
        view3d.tag_redraw()
        return 0.1
    if s.error:
        say("error:", s.error)
    if s.version and s.label not in state["seen"]:
        state["seen"].add(s.label)
        say(f"{elapsed:.2f} s: {s.label}")
    if not s.done:
        return 0.1
    say("session stats", {k: (round(v, 3) if isinstance(v, float) else [round(x, 3) for x in v])
                          for k, v in s.stats.items() if k != "started"},
        "passes", s.passes_run, "size", s.size, "denoise", s.values["denoise"])
    if state["step"] == "first":
        state["step"], state["t0"] = "move", time.perf_counter()
        cube.location.x -= 0.6
    elif state["step"] == "move":
        say("log", vp.log)
        state["step"], state["t0"] = "restyle", time.perf_counter()
        st.params.cel__levels = "0.15,0.55,1.0"
        view3d.tag_redraw()
        return 1.0
    elif state["step"] == "restyle":
        say("log", vp.log[-2:])
        state["step"] = "shoot"
        return 1.0
    elif state["step"] == "shoot":
        shoot()
        return None
    return 0.2


def shoot():
    full = os.path.join(links, "window.png")
    with bpy.context.temp_override(window=window, screen=window.screen, area=view3d):
        bpy.ops.screen.screenshot(filepath=full)
    box = (view3d.x, view3d.y, view3d.width, view3d.height)
    try:
        import numpy as np
        from PIL import Image
    except ImportError:
        os.replace(full, OUT)
    else:
        img = np.asarray(Image.open(full))
        h = img.shape[0]
        x, y, w, hh = box
        Image.fromarray(img[h - (y + hh):h - y, x:x + w]).save(OUT)
    say("screenshot written:", OUT, "view", box, bpy.app.version_string)
    bpy.ops.wm.quit_blender()


bpy.app.timers.register(step, first_interval=1.0)
