"""Remake docs/interactive_viewport.png: Blender's 3D viewport in Rendered shading with styletrace's
engine and the cel style, screenshotted after an edit when it first draws the first clean image,
and at the session's last image (docs/blender.md, Viewport).

Run by Blender itself (a GUI: `bpy` as a module draws nothing), e.g. Debian's Blender 3.4 under
Xvfb, from the repository's root (LD_PRELOAD: docs/make_blender_viewport.py says why):

    LD_PRELOAD=/lib/x86_64-linux-gnu/libhwloc.so.15 \\
    STYLETRACE_SITE=.venv/lib/python3.11/site-packages \\
    xvfb-run -a -s "-screen 0 512x512x24" blender --factory-startup \\
        --python docs/make_interactive_screenshot.py

The scene is tests/blender/scenes.py's `interior` (a room lit through a window: sun and sky, a
ceiling lamp, a glossy floor, a mirror beside the camera and out of its view, Principled
materials), its module loaded by path with a `reset` for the GUI (no factory settings read in the
builder, which runs in the window's context, and no EXR output settings: Blender 5's names, F12
only); on Blender 3.x its Principled inputs are given 3.x's names, which the add-on reads as 4.x's
(`materials.principled_sockets`). The 3D view fills the window (no other area, header, toolbar,
overlay or gizmo) and looks through the scene camera, its frame fitted to the region: 512x512 in a
512x512 screen.

The render engine is styletrace with the cel style and every other setting at its default (Samples
16: four passes of one camera sample of 4 children; Denoise auto: the expectation denoiser: 512x512
pixels at 4 camera samples fit the buffer's cap). The view switches to Rendered shading; once the
first session has ended (its kernels compiled) and its last image is drawn, the vase (the sphere on
the table) moves 0.2 m along -x, towards the camera: an edit, the clock's zero. Each image the view
draws after it is noted with its label and the seconds from the edit to its first draw
(`viewport_hooks.view_draw` wrapped; an image the worker replaced during the draw is not counted).
Blender's screenshot (`screen.screenshot`, cropped to the view's region) is taken on the main
thread's next timer tick after the first draw of the first image whose label matches
STYLETRACE_SHOT_LABEL (an fnmatch pattern; default `pass 1/*, denoised (preview)`: the first
full-size denoised image), and again once the session has ended, of its last image; a shot whose
image was replaced before it was taken fails the run. Each shot is checked against the session's
image: the mean and largest difference in 8-bit levels from 255 sRGB(clip(image)), inside the
area's 1-pixel border (Blender's dither: about 0.4 on average, 1.4 at most); a mean over
SAME_LEVELS fails the run (another pass's image differs by about 7). A draft, smaller than the
region and drawn stretched, is not compared.

Writes docs/interactive_viewport.png (STYLETRACE_SHOT: another path): the two shots side by side,
each captioned with its label and the seconds since the edit; prints the timings as
`interactive screenshot:` lines. Exit status 0, or 1 on a timeout (STYLETRACE_SHOT_TIMEOUT
seconds in all, default 900), a session's error or a failed shot.
"""
import fnmatch
import importlib.util
import io
import os
import sys
import time
import traceback
from importlib import import_module

import bpy

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)
OUT = os.environ.get("STYLETRACE_SHOT", os.path.join(HERE, "interactive_viewport.png"))
LABEL = os.environ.get("STYLETRACE_SHOT_LABEL", "pass 1/*, denoised (preview)")
TIMEOUT_S = float(os.environ.get("STYLETRACE_SHOT_TIMEOUT", "900"))
SIZE = 512
#: the edit: the vase's move along x (towards the camera), in metres
MOVE_X = -0.2
#: the most a screenshot may differ from its image, mean levels inside the border (dither: 0.37)
SAME_LEVELS = 1.0
#: the main thread's polling interval (the screenshot follows the first draw by at most this)
TICK_S = 0.01

sys.path.insert(0, os.path.join(ROOT, "src"))
links = import_module("styletrace.blender.borrowed_site").borrow_site(ROOT)  # with the denoiser

# styletrace and its dependencies are importable only now: loaded by name
np = import_module("numpy")
Image = import_module("PIL.Image")
ImageDraw = import_module("PIL.ImageDraw")
ImageFont = import_module("PIL.ImageFont")
addon = import_module("styletrace.blender")
viewport = import_module("styletrace.blender.viewport_hooks")
materials = import_module("styletrace.blender.materials")
images = import_module("styletrace.images")


def say(*args):
    print("interactive screenshot:", *args, flush=True)


def scenes_module():
    """tests/blender/scenes.py, loaded by path, with `reset` for the GUI and, on Blender 3.x,
    its materials' 4.x input names given as 3.x's."""
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
            """`material` with 3.x's names of the Principled inputs 4.0 renamed."""
            if kind == "ShaderNodeBsdfPrincipled":
                names = materials.PRINCIPLED_3X_NAMES
                inputs = {names.get(k, k): v for k, v in inputs.items()}
            return material(name, kind, **inputs)
        S.material = material_3x
    return S


def view_3d():
    """(window, area, region, space) of the 3D view."""
    window = bpy.context.window_manager.windows[0]
    area = next(a for a in window.screen.areas if a.type == "VIEW_3D")
    region = next(r for r in area.regions if r.type == "WINDOW")
    return window, area, region, area.spaces.active


def setup_view():
    """The 3D view alone in the window, nothing drawn over the engine's image, through the scene
    camera with its frame fitted to the region (as benchmarks/blender_viewport.py)."""
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
    return np.ascontiguousarray(img[img.shape[0] - (y + h):img.shape[0] - y, x:x + w])


def srgb8(image):
    """255 sRGB(clip(image)) of a linear image: what the Standard view transform draws."""
    x = np.clip(image, 0.0, 1.0)
    return 255.0 * np.where(x <= 0.0031308, 12.92 * x, 1.055 * x ** (1 / 2.4) - 0.055)


class Draws:
    """The images the view draws, each noted at its first draw (`viewport_hooks.view_draw`
    wrapped)."""

    def __init__(self):
        self.t0 = None  # the edit's time; None: nothing is noted yet
        self.seen = []  # (seconds since the edit, label, image) of each image at its first draw
        self.last = None  # the image drawn last (any draw, before the edit too)

    def wrap(self):
        original = viewport.view_draw

        def view_draw(engine, context, depsgraph):
            vp = viewport.VIEWS.get(engine.as_pointer())
            s = vp.session if vp is not None else None
            image, label = s.latest() if s is not None else (None, "")
            original(engine, context, depsgraph)
            # the image drawn is `image` only where the session and its newest image are the same
            # after the draw (the worker replaces images; a view change starts a new session)
            if image is None or vp.session is not s or s.latest()[0] is not image:
                self.last = None
                return
            if image is not self.last and self.t0 is not None:
                self.seen.append((time.perf_counter() - self.t0, label, image))
            self.last = image
        viewport.view_draw = view_draw  # the engine calls it through the module


def session():
    views = list(viewport.VIEWS.values())
    return (views[0], views[0].session) if views else (None, None)


def shoot(draws, entry, path):
    """The region's screenshot, checked to show `entry`'s image; returns the shot (uint8 RGB) and
    its (mean, largest) difference in levels from the image's 8-bit rendering."""
    _, label, image = entry
    taken = time.perf_counter() - draws.t0
    shot = grab(path)
    _, s = session()
    if draws.last is not image or s is None or s.latest()[0] is not image:
        raise RuntimeError(f"the image {label!r} was replaced before its screenshot")
    if shot.shape[:2] != image.shape[:2]:  # a draft, drawn stretched
        say(f"shot {label!r}: first drawn {entry[0]:.2f} s after the edit, screenshot at "
            f"{taken:.2f} s; a {image.shape[1]}x{image.shape[0]} image stretched: not compared")
        return shot
    # the outermost pixels are the area's border, drawn over the image
    diff = np.abs(shot.astype(np.float64) - srgb8(image))[1:-1, 1:-1]
    say(f"shot {label!r}: first drawn {entry[0]:.2f} s after the edit, screenshot at "
        f"{taken:.2f} s; inside the border it differs from the image by {diff.mean():.2f} "
        f"levels on average, {diff.max():.2f} at most")
    if diff.mean() > SAME_LEVELS:
        raise RuntimeError(f"the screenshot does not show the image {label!r}")
    return shot


def caption_font(size):
    try:
        return ImageFont.load_default(size=size)  # Pillow >= 10.1, with FreeType
    except TypeError:
        return ImageFont.load_default()


def compose(shots, captions):
    """The shots side by side on white, each with its two caption lines below; PNG bytes."""
    font = caption_font(16)
    h, w = shots[0].shape[:2]
    gap, pad, line = 12, 8, 21
    sheet = Image.new("RGB", (len(shots) * w + (len(shots) - 1) * gap,
                              h + 2 * pad + len(captions[0]) * line), "white")
    draw = ImageDraw.Draw(sheet)
    for k, (shot, lines) in enumerate(zip(shots, captions)):
        x = k * (w + gap)
        sheet.paste(Image.fromarray(shot), (x, 0))
        for j, text in enumerate(lines):
            draw.text((x + 4, h + pad + j * line), text, fill="black", font=font)
    buf = io.BytesIO()
    sheet.save(buf, format="PNG", optimize=True)
    return buf.getvalue()


def run(draws):
    """Generator stepped by the timer (yields seconds to wait)."""
    start = time.perf_counter()
    shot_path = os.path.join(links, "window.png")

    def waited():
        if time.perf_counter() - start > TIMEOUT_S:
            raise TimeoutError(f"over {TIMEOUT_S:.0f} s")
        _, s = session()
        if s is not None and s.error:
            raise RuntimeError(f"the session's error: {s.error}")
        return TICK_S

    try:
        import pyoidn  # noqa: F401
        say("denoiser: pyoidn", pyoidn.__file__)
    except ImportError as exc:
        say("denoiser unavailable:", exc)
    S = scenes_module()
    addon.register()
    draws.wrap()
    bpy.ops.wm.read_factory_settings(use_empty=True)  # a fresh file, out of the window's context
    yield 0.5
    window, area, region, _ = view_3d()
    with bpy.context.temp_override(window=window, screen=window.screen, area=area,
                                   region=region):
        S.interior(SIZE)
    scene = bpy.context.scene
    scene.render.engine = "STYLETRACE"
    st = scene.styletrace
    st.style = "cel"  # every other setting at its default
    setup_view()
    yield 1.0
    _, area, region, space = view_3d()
    say(f"Blender {bpy.app.version_string}; region {region.width}x{region.height}; samples "
        f"{st.samples}, camera samples {st.spp} (0: auto), pass {st.pass_spp}, denoise "
        f"{st.denoise}; shot label pattern {LABEL!r}")
    space.shading.type = "RENDERED"
    area.tag_redraw()
    t_switch = time.perf_counter()
    seen = set()
    while True:  # the first session: kernels compiled
        vp, s = session()
        if s is not None and s.version and s.label not in seen:
            seen.add(s.label)
            say(f"first session: {time.perf_counter() - t_switch:.2f} s after the switch: "
                f"{s.label}")
        if s is not None and s.done and draws.last is not None and s.latest()[0] is draws.last:
            break
        yield waited()
    say(f"first session ended {time.perf_counter() - t_switch:.2f} s after the switch")
    yield 1.0
    before = s
    vase = bpy.data.objects["Sphere"]
    draws.t0 = time.perf_counter()
    vase.location.x += MOVE_X
    first = last = None
    while last is None:
        yield waited()
        vp, s = session()
        if first is None:
            entry = next((e for e in draws.seen if fnmatch.fnmatchcase(e[1], LABEL)), None)
            if entry is not None:
                first = entry, shoot(draws, entry, shot_path)
        if (s is not before and s.done and draws.seen and draws.seen[-1][2] is draws.last
                and s.latest()[0] is draws.last):
            if first is None:
                raise RuntimeError(f"no image labelled {LABEL!r} was drawn; drawn: "
                                   f"{[label for _, label, _ in draws.seen]}")
            last = draws.seen[-1], shoot(draws, draws.seen[-1], shot_path)
    entry = vp.log[-1]
    say(f"the edit's sync: {entry['kind']} {entry['objects']} in {entry['seconds'] * 1e3:.1f} ms")
    for t, label, _ in draws.seen:
        say(f"{t:.2f} s after the edit: {label}")
    say("session stats", {k: (round(v, 3) if isinstance(v, float) else [round(x, 3) for x in v])
                          for k, v in s.stats.items() if k != "started"},
        "passes", s.passes_run, "size", s.size)
    captions = [[label, f"{t:.1f} s after the edit"] for (t, label, _), _ in (first, last)]
    data = compose([first[1], last[1]], captions)
    images.write_bytes_atomically(data, OUT)
    say(f"written {OUT} in {time.perf_counter() - start:.0f} s")


def main():
    draws, steps = Draws(), None

    def tick():
        nonlocal steps
        try:
            if steps is None:
                steps = run(draws)
            return max(0.0, next(steps))
        except StopIteration:
            sys.stdout.flush()
            os._exit(0)  # quit_blender would save preferences and wait
        except Exception:
            traceback.print_exc()
            say("failed")
            sys.stdout.flush()
            os._exit(1)

    bpy.context.preferences.view.show_splash = False
    bpy.app.timers.register(tick, first_interval=1.0, persistent=True)  # survives file loads


main()
