"""Blender's side of test_viewport_draw.py: run by a real Blender (a GUI under Xvfb), not by pytest.

    STYLETRACE_SITE=.venv/lib/python3.11/site-packages STYLETRACE_DRAW_OUT=DIR \\
    xvfb-run -a -s "-screen 0 640x400x24" blender --factory-startup \\
        --python tests/blender/viewport_draw_blender.py

Builds a small scene (a cube on a floor, a sphere, a sun; the identity style, 4 spp), shows it in
the 3D view's Rendered shading with no overlay, gizmo or region but the view's own, waits for the
session's last pass, then writes to DIR, per phase, `NAME.png.npy` (the region's pixels cropped from
`screen.screenshot`, top row first, uint8 RGB) and `NAME.image.npy` (the session's `latest()` image
drawn then, linear float32, top row first). Phases: `standard` (view transform Standard, exposure 0,
no dither), `exposure` (exposure +1) and three draws broken on purpose (`hooks.draw_view_image`
replaced): `flipped` (upside down), `encoded` (sRGB-encoded before the draw) and `unbound` (no
`bind_display_space_shader`). `log.json`: what each phase saw; exit status 0 when every phase ran, 1
otherwise (a timeout or an error; `log.json` says which). """
import json
import math
import os
import sys
import time
import traceback
from importlib import import_module

import bpy
import gpu
from gpu_extras.presets import draw_texture_2d
from mathutils import Quaternion

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
OUT = os.environ["STYLETRACE_DRAW_OUT"]
TIMEOUT_S = float(os.environ.get("STYLETRACE_DRAW_TIMEOUT", "90"))
SPP = 4

sys.path.insert(0, os.path.join(ROOT, "src"))
site = import_module("styletrace.blender.borrowed_site")
# without the denoiser, as before: in Debian's Blender 3.4 a denoise needs libhwloc preloaded
# (docs/make_blender_viewport.py), and the draft's denoising is not what this test reads
links = site.borrow_site(ROOT, site.PACKAGES + ("pyoidn",), links=os.path.join(OUT, "site"))

# styletrace and its dependencies are importable only now: loaded by name
np = import_module("numpy")
Image = import_module("PIL.Image")
blender = import_module("styletrace.blender")
hooks = import_module("styletrace.blender.viewport_hooks")

LOG = {"blender": bpy.app.version_string, "phases": {}, "error": None}


def build_scene():
    """The scene and the 3D view: Rendered shading, nothing drawn over the engine's image."""
    blender.register()
    scene = bpy.context.scene
    scene.render.engine = "STYLETRACE"
    st = scene.styletrace
    st.style = "identity"
    st.spp, st.pass_spp, st.seed = SPP, 2, 1
    vs = scene.view_settings
    vs.view_transform, vs.look, vs.exposure, vs.gamma = "Standard", "None", 0.0, 1.0
    vs.use_curve_mapping = False
    scene.display_settings.display_device = "sRGB"
    scene.sequencer_colorspace_settings.name = "sRGB"
    scene.render.dither_intensity = 0.0  # the display transform's noise: off, for exact levels
    cube = bpy.data.objects["Cube"]
    cube.location = (0.0, 0.0, 1.0)
    bpy.ops.mesh.primitive_plane_add(size=14, location=(0, 0, 0))
    bpy.ops.mesh.primitive_uv_sphere_add(radius=0.8, location=(2.2, 0.8, 0.8))
    for name, colour in (("Cube", (0.8, 0.25, 0.15)), ("Plane", (0.75, 0.75, 0.7)),
                         ("Sphere", (0.2, 0.45, 0.8))):
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
    sun = bpy.data.lights.new("sun", "SUN")
    sun.energy = 3.0
    sun_obj = bpy.data.objects.new("sun", sun)
    scene.collection.objects.link(sun_obj)
    sun_obj.rotation_euler = (math.radians(40), 0, math.radians(30))
    world = scene.world
    world.use_nodes = True
    world.node_tree.nodes["Background"].inputs["Color"].default_value = (0.5, 0.6, 0.8, 1.0)
    world.node_tree.nodes["Background"].inputs["Strength"].default_value = 0.6

    bpy.context.preferences.view.show_splash = False
    window = bpy.context.window_manager.windows[0]
    area = next(a for a in window.screen.areas if a.type == "VIEW_3D")
    space = area.spaces.active
    space.overlay.show_overlays = False
    space.show_gizmo = False
    for flag in ("header", "tool_header", "toolbar", "ui", "hud"):
        setattr(space, f"show_region_{flag}", False)
    rv3d = space.region_3d
    rv3d.view_perspective = "PERSP"
    rv3d.view_distance = 11.0
    rv3d.view_rotation = Quaternion((0.82, 0.42, 0.18, 0.34)).normalized()
    rv3d.view_location = (0.5, 0.3, 0.6)
    space.shading.type = "RENDERED"
    return scene, window, area


def flipped(draw):
    return lambda engine, scene, image, w, h: draw(engine, scene, image[::-1], w, h)


def encoded(draw):
    def srgb(x):
        x = np.clip(x, 0.0, 1.0)
        return np.where(x <= 0.0031308, 12.92 * x, 1.055 * x ** (1 / 2.4) - 0.055)
    return lambda engine, scene, image, w, h: draw(engine, scene, srgb(image), w, h)


def unbound(draw):
    """`hooks.draw_view_image` without `bind_display_space_shader` (its texture, drawn as it
    draws it)."""
    def body(engine, scene, image, width, height):
        texture = hooks.view_texture(image)
        gpu.state.blend_set("ALPHA_PREMULT")
        offset = -hooks.PIXEL_OFFSET
        draw_texture_2d(texture, (offset, offset), width, height)
        gpu.state.blend_set("NONE")
    return body


class Run:
    """The phases, stepped by a timer on Blender's main thread."""

    def __init__(self, scene, window, area):
        self.scene, self.window, self.area = scene, window, area
        self.draw = hooks.draw_view_image
        self.phases = [("standard", None, 0.0), ("exposure", None, 1.0),
                       ("flipped", flipped, 0.0), ("encoded", encoded, 0.0),
                       ("unbound", unbound, 0.0)]
        self.phase = None
        self.t0 = self.start = time.perf_counter()
        self.calls = 0

    def counted(self, draw):
        def wrapped(*args):
            self.calls += 1
            return draw(*args)
        return wrapped

    def begin(self):
        name, broken, exposure = self.phase = self.phases.pop(0)
        self.calls, self.t0 = 0, time.perf_counter()
        self.scene.view_settings.exposure = exposure
        hooks.draw_view_image = self.counted(broken(self.draw) if broken else self.draw)
        self.area.tag_redraw()

    def step(self):
        try:
            return self._step()
        except Exception:
            LOG["error"] = traceback.format_exc()
            return self.finish()

    def _step(self):
        if time.perf_counter() - self.start > TIMEOUT_S:
            LOG["error"] = f"timed out in phase {self.phase and self.phase[0]}"
            return self.finish()
        views = list(hooks.VIEWS.values())
        vp = views[0] if views else None
        s = vp.session if vp else None
        if s is None or not s.done or s.version == 0:
            self.area.tag_redraw()
            return 0.1
        if s.error:
            LOG["error"] = f"session: {s.error}"
            return self.finish()
        if self.phase is None:
            self.begin()
            return 0.1
        # the session's last image drawn by this phase's draw, then one more loop for the swap
        if vp.drawn != s.version or self.calls == 0:
            self.area.tag_redraw()
            return 0.1
        self.shoot(vp, s)
        if not self.phases:
            return self.finish()
        self.begin()
        return 0.1

    def shoot(self, vp, s):
        name = self.phase[0]
        full = os.path.join(links, "window.png")
        with bpy.context.temp_override(window=self.window, screen=self.window.screen,
                                       area=self.area):
            bpy.ops.screen.screenshot(filepath=full)
        region = next(r for r in self.area.regions if r.type == "WINDOW")
        img = np.asarray(Image.open(full))
        x, y, w, h = region.x, region.y, region.width, region.height
        crop = img[img.shape[0] - (y + h):img.shape[0] - y, x:x + w]
        image, label = s.latest()
        np.save(os.path.join(OUT, f"{name}.png.npy"), crop)
        np.save(os.path.join(OUT, f"{name}.image.npy"), image)
        LOG["phases"][name] = {
            "label": label, "region": [x, y, w, h], "window": list(img.shape),
            "image": list(image.shape), "session": id(s), "passes": s.passes_run,
            "draws": self.calls, "seconds": round(time.perf_counter() - self.t0, 3),
            "exposure": self.scene.view_settings.exposure,
            "updates": [e["kind"] for e in vp.log]}

    def finish(self):
        hooks.draw_view_image = self.draw
        LOG["seconds"] = round(time.perf_counter() - self.start, 3)
        with open(os.path.join(OUT, "log.json"), "w") as f:
            json.dump(LOG, f, indent=1)
        sys.stdout.flush()
        os._exit(1 if LOG["error"] else 0)  # quit_blender would save preferences and wait


run = Run(*build_scene())
bpy.app.timers.register(run.step, first_interval=0.5)
