"""Blender's 3D viewport in Rendered shading: styletrace's engine against Cycles' on the same
scenes.

Run by Blender itself (a GUI: `bpy` as a module draws nothing), e.g. Debian's Blender 3.4 under
Xvfb, as docs/make_blender_viewport.py (LD_PRELOAD: see there):

    LD_PRELOAD=/lib/x86_64-linux-gnu/libhwloc.so.15 \\
    STYLETRACE_SITE=/path/to/.venv/lib/python3.11/site-packages \\
    xvfb-run -a -s "-screen 0 400x300x24" blender --factory-startup \\
        --python benchmarks/blender_viewport.py

Scenes: tests/blender/scenes.py's room, glossy and textured_plane, its module loaded by path. Two
changes for Blender 3.x: its `reset` is replaced by one without the EXR output settings (Blender
5's names, used by F12 only) that reads the factory settings before the builder runs in the
window's context; and on 3.x, whose Principled BSDF the add-on does not read (it expects 4.x's
input names), the scenes' Principled materials (rough, no specular: the room's green wall, the
textured plane) become Diffuse BSDFs of the same colour or texture, for both engines.

The 3D view fills the window (no other area, header, toolbar or overlay) and looks through the
scene camera, its frame fitted to the region (400x300 in a 400x300 screen). Per scene and engine
(Cycles on the CPU at its viewport defaults; styletrace at its defaults with the identity style,
then with cel) the view is switched from Solid to Rendered shading and the region is cropped from
Blender's screenshot (`screen.screenshot`) every 0.25 s, for at most 60 s (STYLETRACE_VPB_SECONDS):
styletrace's run ends a second after its session's last image is drawn, Cycles' after 10 s without
change. From the frames (8-bit sRGB, mean absolute difference over pixels and channels, in levels):
first image = the first frame more than 3 levels from the Solid frame before the switch; settled =
the last frame more than 1 level from the final frame. Dither is off (display noise in every
frame). Writes the `blender_viewport` section of BENCHMARKS.md; STYLETRACE_VPB_SCENES=room,glossy
picks scenes, STYLETRACE_VPB_NO_WRITE=1 only prints.
"""
import importlib.util
import os
import sys
import time
import traceback
from importlib import import_module
from types import SimpleNamespace

import bpy

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)
SCENE_NAMES = os.environ.get("STYLETRACE_VPB_SCENES", "room,glossy,textured_plane").split(",")
ENGINES = (("Cycles", "CYCLES", None), ("styletrace identity", "STYLETRACE", "identity"),
           ("styletrace cel", "STYLETRACE", "cel"))
MAX_S = float(os.environ.get("STYLETRACE_VPB_SECONDS", "60"))
STEP_S = 0.25
FIRST_LEVELS, SETTLED_LEVELS = 3.0, 1.0
WIDTH, HEIGHT = 400, 300

sys.path[:0] = [os.path.join(ROOT, "src"), HERE]
links = import_module("styletrace.blender.borrowed_site").borrow_site(ROOT)  # with the denoiser

# styletrace, its dependencies and the report's plumbing are importable only now: loaded by name
np = import_module("numpy")
Image = import_module("PIL.Image")
addon = import_module("styletrace.blender")
viewport = import_module("styletrace.blender.viewport_hooks")
report = import_module("_report")


def scenes_module():
    """tests/blender/scenes.py, loaded by path; on Blender 3.x its materials' Blender 4 socket
    name "Specular IOR Level" is given as 3.x's "Specular"."""
    spec = importlib.util.spec_from_file_location(
        "scenes", os.path.join(ROOT, "tests", "blender", "scenes.py"))
    S = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(S)
    def reset_view(size=64):
        """`reset` without the factory settings (read before, out of the window's context) or the
        EXR output settings (Blender 5's `media_type`; F12 only)."""
        s = bpy.context.scene
        s.render.resolution_x = s.render.resolution_y = size
        s.render.resolution_percentage = 100
        s.render.threads_mode, s.render.threads = "FIXED", 2
        s.view_settings.view_transform = "Standard"
        s.world = bpy.data.worlds.new("world")
        s.world.use_nodes = True
        s.world.node_tree.nodes["Background"].inputs["Strength"].default_value = 0.0
        return s
    S.reset = reset_view
    if bpy.app.version < (4, 0, 0):
        material = S.material

        def material_3x(name, kind="ShaderNodeBsdfDiffuse", **inputs):
            """Blender 3.x's Principled BSDF has other input names than 4.x's, which the add-on
            reads: a Diffuse BSDF of its base colour instead (the scenes' are rough and without
            specular), returned with its colour input under "Base Color"."""
            if kind != "ShaderNodeBsdfPrincipled":
                return material(name, kind, **inputs)
            colour = {"Color": inputs["Base Color"]} if "Base Color" in inputs else {}
            mat, node = material(name, "ShaderNodeBsdfDiffuse", **colour)
            return mat, SimpleNamespace(inputs={"Base Color": node.inputs["Color"]})
        S.material = material_3x
    return S


def say(*args):
    print("blender_viewport:", *args, flush=True)


def view_3d():
    """(window, area, region, space) of the 3D view, which fills the window."""
    window = bpy.context.window_manager.windows[0]
    area = next(a for a in window.screen.areas if a.type == "VIEW_3D")
    region = next(r for r in area.regions if r.type == "WINDOW")
    return window, area, region, area.spaces.active


def setup_view():
    """The 3D view alone in the window, nothing drawn over the engine's image, through the scene
    camera with its frame fitted to the region."""
    window, area, region, space = view_3d()
    if len(window.screen.areas) > 1:
        with bpy.context.temp_override(window=window, screen=window.screen, area=area,
                                       region=region):
            bpy.ops.screen.screen_full_area(use_hide_panels=True)
        window, area, region, space = view_3d()
    space.overlay.show_overlays = False
    space.show_gizmo = False
    for flag in ("header", "tool_header", "toolbar", "ui", "hud"):
        setattr(space, f"show_region_{flag}", False)
    space.shading.type = "SOLID"
    space.region_3d.view_perspective = "CAMERA"
    with bpy.context.temp_override(window=window, screen=window.screen, area=area,
                                   region=region):
        bpy.ops.view3d.view_center_camera()
    area.tag_redraw()


def grab(path):
    """The region's pixels (top row first, uint8 RGB) from Blender's screenshot of the window."""
    window, area, region, _ = view_3d()
    with bpy.context.temp_override(window=window, screen=window.screen, area=area):
        bpy.ops.screen.screenshot(filepath=path)
    img = np.asarray(Image.open(path))[..., :3]
    x, y, w, h = region.x, region.y, region.width, region.height
    return img[img.shape[0] - (y + h):img.shape[0] - y, x:x + w].astype(np.float32)


def mad(a, b):
    return float(np.abs(a - b).mean())


def session():
    views = list(viewport.VIEWS.values())
    return (views[0], views[0].session) if views else (None, None)


def measure(scene_name, label, engine, style, shot):
    """Generator stepped by the timer (yields seconds to wait): one engine's run on the scene
    built; returns its row."""
    scene = bpy.context.scene
    scene.render.engine = engine
    if style:
        scene.styletrace.style = style
    setup_view()
    yield 1.0
    base = grab(shot)
    for key in list(viewport.VIEWS):  # the engines of the file before: freed with it
        viewport.free_key(key)
    _, area, region, space = view_3d()
    space.shading.type = "RENDERED"
    area.tag_redraw()
    t0 = time.perf_counter()
    times, frames, info, done_at = [], [], "", None
    while True:
        yield STEP_S - (time.perf_counter() - t0) % STEP_S
        t = time.perf_counter() - t0
        frames.append(grab(shot))
        times.append(t)
        if engine == "STYLETRACE":
            vp, s = session()
            if s is not None:
                info = f"{s.label}; passes {s.passes_run}" + (f"; error {s.error}" if s.error
                                                                else "")
                if s.done and vp.drawn == s.version and done_at is None:
                    done_at = t
            if done_at is not None and t - done_at > 1.0:
                break
        else:
            quiet = [k for k in range(len(frames)) if times[-1] - times[k] <= 10.0]
            if (times[-1] - times[quiet[0]] >= 9.5 and mad(frames[quiet[0]], base) > FIRST_LEVELS
                    and all(mad(frames[k], frames[-1]) < 0.05 for k in quiet)):
                break
        if t >= MAX_S:
            break
    space.shading.type = "SOLID"
    area.tag_redraw()
    final = frames[-1]
    first = next((t for t, f in zip(times, frames) if mad(f, base) > FIRST_LEVELS), None)
    settled = max((t for t, f in zip(times, frames) if mad(f, final) > SETTLED_LEVELS),
                  default=times[0])
    # still changing when the run stopped: the final frame against the one a second earlier
    earlier = [f for t, f in zip(times, frames) if times[-1] - t >= 1.0]
    change = mad(earlier[-1], final) if earlier else 0.0
    row = {"scene": scene_name, "engine": label, "region": f"{region.width}x{region.height}",
           "first": first, "settled": settled, "end": times[-1], "last_s_change": change,
           "frames": len(frames), "info": info}
    say(row)
    yield 1.0
    return row


def table(rows):
    lines = ["| scene | engine | first image s | settled s | run s | change in its last second, "
             "levels |", "|---|---|---|---|---|---|"]
    for r in rows:
        first = "never" if r["first"] is None else f"{r['first']:.2f}"
        lines.append(f"| {r['scene']} | {r['engine']} | {first} | {r['settled']:.2f} | "
                     f"{r['end']:.1f} | {r['last_s_change']:.2f} |")
    return "\n".join(lines)


def run(rows):
    shot = os.path.join(links, "window.png")
    S = scenes_module()
    addon.register()
    for name in SCENE_NAMES:
        for label, engine, style in ENGINES:
            # a fresh scene per run (nothing cached in the engine's view), built in the window's
            # context (operators and `context.object`)
            bpy.ops.wm.read_factory_settings(use_empty=True)
            yield 0.5
            window, area, region, _ = view_3d()
            with bpy.context.temp_override(window=window, screen=window.screen, area=area,
                                           region=region):
                S.SCENES[name](WIDTH)
            scene = bpy.context.scene
            scene.render.resolution_x, scene.render.resolution_y = WIDTH, HEIGHT
            scene.render.dither_intensity = 0.0
            row = yield from measure(name, label, engine, style, shot)
            rows.append(row)
    runs = (f"{len(rows)} runs" if rows else "no runs")
    say("table", runs)
    print(table(rows), flush=True)
    cy, st = bpy.context.scene.cycles, bpy.context.scene.styletrace
    body = "\n".join([
        "## Blender viewport against Cycles (benchmarks/blender_viewport.py)", "",
        report.machine_description() + f"; Blender {bpy.app.version_string} under Xvfb", "",
        f"Rendered shading in the 3D view ({rows[0]['region'] if rows else '?'} region, through "
        "the scene camera), from the switch out of Solid shading; the region screenshotted every "
        f"{STEP_S} s for at most {MAX_S:.0f} s. Cycles on the CPU at its viewport defaults "
        f"({cy.preview_samples} samples, adaptive sampling "
        f"{'on' if cy.use_preview_adaptive_sampling else 'off'}, denoising "
        f"{'on' if cy.use_preview_denoising else 'off'}); styletrace at its defaults "
        f"({st.spp} spp in passes of {st.pass_spp}, Denoise {st.denoise}). "
        "Criterion, the same for both: first image = "
        f"the first frame more than {FIRST_LEVELS:.0f} levels (mean absolute difference, 8-bit "
        "sRGB) from the Solid frame; settled = the last frame more than "
        f"{SETTLED_LEVELS:.0f} level from the final frame. Last column: the final frame "
        "against the one a second before (above 0: still changing when the run stopped). "
        "The scenes' Principled materials are Diffuse ones of the same colour or texture for both "
        "engines (the exporter reads Blender 4's Principled sockets).", "",
        table(rows)])
    if not os.environ.get("STYLETRACE_VPB_NO_WRITE"):
        report.write_section("blender_viewport", body)
        say("written", report.REPORT)


def main():
    rows, steps = [], None
    start = time.perf_counter()

    def tick():
        nonlocal steps
        try:
            if steps is None:
                steps = run(rows)
            return max(0.01, next(steps))
        except StopIteration:
            say(f"done in {time.perf_counter() - start:.1f} s")
        except Exception:
            traceback.print_exc()
            say("failed after", rows)
            sys.stdout.flush()
            os._exit(1)
        sys.stdout.flush()
        os._exit(0)  # quit_blender would save preferences and wait

    bpy.context.preferences.view.show_splash = False
    bpy.app.timers.register(tick, first_interval=1.0, persistent=True)  # survives file loads


main()
