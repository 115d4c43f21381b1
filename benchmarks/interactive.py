"""Interactive where artists work: styletrace's viewport against Cycles' on three Blender scenes.

Run with the Blender venv (bpy as a module), on an otherwise idle machine:

    .venv-blender/bin/python benchmarks/interactive.py [--size 512] [--scenes interior,room,glossy]
        [--styles cel] [--no-write]

Scenes: tests/blender/scenes.py's `interior` (a room lit through a window: a sun and a sky
outside, a small lamp, a glossy floor, a mirror, Principled materials), `room` (diffuse, open to
the sky, an area light and a sun) and `glossy` (a glossy sphere under an HDR world and a point
light), at --size square, 2 threads. Writes the BENCHMARKS.md section "Interactive".

styletrace: the viewport's session (`blender.viewport.Viewport`, headless: the images it would
draw, with the time each was ready) at the add-on's defaults (Samples 16, Denoise auto), through
the scene camera. Each run starts with the scene synced and kernels compiled (one untimed session
first), then an object moves (an edit: `EDIT`), and the time counts from the update call. Per
image: its PSNR against a converged render of the same look, and the noise between two runs that
differ only in the seed (both in sRGB, `measures`; a draft smaller than the view is compared
after nearest-neighbour upscaling). Times are medians over TIME_RUNS sessions of the first seed
(the same image's label in each). Reported:
- first image: the first image shown;
- clean: the first full-size image at PSNR >= 30 dB against the converged render, and the noise
  PSNR between the two seeds' images of that state (the same label; else the other seed's image
  on screen at that time);
- done: the session's last image;
- drag (cel): its levels changed ten times in a row, each restyled at one point per pixel: the
  median and largest time from the change (the update call) to its image; rest: the whole
  buffer's restyle after the drag (`Viewport.settle`, which the rest timer runs).
The converged render of the same look: F12 with the same settings and the same children per
camera sample, 256 paths per pixel: for a denoised expectation, whose camera samples its buffer
caps (16 per pixel at 512 x 512), the mean of 4 such renders (seeds 99 to 102).
Cost: each style's render at the defaults through F12, the command line, Python and the preview,
against the identity style's; the viewport's from the timelines.

--camera-move measures only what a camera move shows (`camera_move_rows`): the seconds from the
moved view to the first image, the draft and the first pass, with the image before carried to the
new view (`Viewport.carry`) and without; it writes the section "interactive_camera".

Cycles: Debian's Blender 3.4 (the only windowed Blender here) is built without OIDN, so Cycles'
viewport denoiser cannot run in a window on this machine. Its viewport is measured as F12 renders
with the viewport's settings instead (bpy 5.0): CPU, adaptive sampling at the viewport's threshold
0.1, indirect clamp 10, OIDN on from the first sample with the viewport's guide (albedo) and
prefilter (fast). A render of k samples stands for the viewport's image after k samples: its wall
time includes Cycles' scene sync, as the viewport's re-sync after an edit does, and one denoising
(the viewport denoises at every update: this favours Cycles). k runs 1, 2, 4, ... until clean,
then the viewport's default of 1024 samples (adaptive) for done. Converged: Cycles at 1024 samples,
adaptive threshold 0.01, denoised (its F12 defaults but the sample count).
"""
from __future__ import annotations

import argparse
import os
import statistics
import sys
import tempfile
import time

import bpy
import numpy as np
from _report import image_grid, machine_description, write_section

import styletrace.blender as addon
from styletrace import measures
from styletrace.blender import camera
from styletrace.blender.viewport import Viewport
from styletrace.lookdev.buffer import MAX_CAMERA_SAMPLES

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)
CLEAN_DB = 30.0
SEEDS = (1, 2)
#: sessions of the first seed timed; each image's time is their median
TIME_RUNS = 3
REF_SEED = 99
#: paths per pixel of the converged renders, and how many seeds a capped one averages
REF_PATHS, REF_SEEDS = 256, 4
#: the object each scene moves for its edit, and by how much (metres along x)
EDIT = {"interior": ("Sphere", 0.05), "room": ("Cube", 0.05), "glossy": ("Sphere", 0.05)}
CYCLES_SAMPLES = (1, 2, 4, 8, 16, 32, 64, 128, 256)
#: the style values a drag passes through (cel's levels, brighter each step)
DRAG = tuple(f"{0.05 + 0.01 * i:.2f},0.18,{0.45 + 0.02 * i:.2f}" for i in range(10))


def scenes_module():
    """tests/blender/scenes.py: the scenes live with their tests."""
    sys.path.insert(0, os.path.join(ROOT, "tests", "blender"))
    import scenes

    return scenes


def say(*args) -> None:
    print("interactive:", *args, flush=True)


def psnr(a: np.ndarray, b: np.ndarray) -> float:
    """PSNR in sRGB of image `a` against `b` (peak 1)."""
    mse = float(np.mean((measures.srgb(a) - measures.srgb(b)) ** 2))
    return float("inf") if mse == 0 else 10 * np.log10(1 / mse)


def full_size(img: np.ndarray, h: int, w: int) -> np.ndarray:
    """`img` brought to h x w by nearest-neighbour sampling (a draft smaller than the view)."""
    if img.shape[:2] == (h, w):
        return img
    ys = (np.arange(h) * img.shape[0] // h).clip(0, img.shape[0] - 1)
    xs = (np.arange(w) * img.shape[1] // w).clip(0, img.shape[1] - 1)
    return img[ys][:, xs]


# ---- styletrace -------------------------------------------------------------------------------

def build(S, name: str, size: int, style: str, seed: int):
    """Scene `name` at `size`, the styletrace engine at its defaults with `style` and `seed`."""
    S.SCENES[name](size)
    scene = bpy.context.scene
    scene.render.engine = "STYLETRACE"
    st = scene.styletrace
    st.style, st.seed = style, seed
    return scene, st


def session_timeline(S, name: str, size: int, style: str, seed: int) -> dict:
    """The viewport's images after an edit: [(seconds, label, image)], and the drag's times."""
    scene, st = build(S, name, size, style, seed)
    dg = bpy.context.evaluated_depsgraph_get()
    vp = Viewport()
    vp.set_sensor(camera.sensor(dg.scene_eval, st.samples))
    vp.update(dg, st)
    vp.session.join(600)  # the untimed session: sync, kernels
    obj, dx = EDIT[name]
    bpy.data.objects[obj].location.x += dx
    images: list = []
    start = [0.0]

    def shown():
        s = vp.session
        image, label = s.latest()
        images.append((time.perf_counter() - start[0], label, image))

    vp.on_image = shown
    start[0] = time.perf_counter()
    vp.update(bpy.context.evaluated_depsgraph_get(), st)
    vp.session.join(600)
    session_images = list(images)  # the drag's restyles below are not the session's
    drag, rest = drag_times(vp, st) if style == "cel" else ([], None)
    vp.close()
    return {"images": session_images, "drag": drag, "rest": rest}


def drag_times(vp, st) -> tuple[list[float], float | None]:
    """Seconds from each of a drag's changes to its image (the update call, which restyles at one
    point per pixel), and of the restyle at rest (`Viewport.settle`, what the rest timer runs)."""
    times = []
    for value in DRAG:
        st.params.cel__levels = value
        start = time.perf_counter()
        entry = vp.update(bpy.context.evaluated_depsgraph_get(), st)
        if entry["kind"] != "restyle":
            return [], None
        times.append(time.perf_counter() - start)
    start = time.perf_counter()
    vp.settle()
    return times, time.perf_counter() - start


def reference(S, name: str, size: int, style: str, tmp: str, n: int) -> np.ndarray:
    """The converged render of the viewport's look: F12 with the same children per camera sample
    (n) and REF_PATHS paths per pixel; a denoised expectation's camera samples are capped by its
    buffer (16 per pixel at 512 x 512), so its reference is the mean of REF_SEEDS renders."""
    images = []
    for seed in range(REF_SEED, REF_SEED + (REF_SEEDS if n > 1 else 1)):
        scene, st = build(S, name, size, style, seed)
        st.inner_samples = str(n)
        st.spp = min(REF_PATHS // n, MAX_CAMERA_SAMPLES // (size * size)) if n > 1 else REF_PATHS
        st.pass_spp = 4
        images.append(S.f12(os.path.join(tmp, f"ref-{name}-{style}.exr"))["Combined"][..., :3])
    return np.mean(images, axis=0)


def styletrace_row(S, name: str, size: int, style: str, tmp: str) -> dict:
    runs = [session_timeline(S, name, size, style, SEEDS[0]) for _ in range(TIME_RUNS)]
    runs.append(session_timeline(S, name, size, style, SEEDS[1]))
    n = children(S, name, size, style)
    ref = reference(S, name, size, style, tmp, n)
    h, w = ref.shape[:2]
    a, b = runs[0]["images"], runs[-1]["images"]
    # each image's time: the median over the first seed's sessions that showed it (the shared
    # cores' speed varies from run to run by up to 2x)
    when = {label: statistics.median(t for r in runs[:TIME_RUNS] for t, shown, _ in r["images"]
                                     if shown == label) for _, label, _ in a}
    rows = []
    by_label = {label: img for _, label, img in b}
    for _, label, img in a:
        t = when[label]
        # the other seed's image of the same state (label), else the one on screen at that time
        pair = by_label.get(label)
        if pair is None:
            pair = next((o for u, _, o in reversed(b) if u <= t), b[0][2])
        rows.append({"t": t, "label": label, "full": img.shape[:2] == (h, w),
                     "ref": psnr(full_size(img, h, w), ref),
                     "seeds": measures.noise_psnr(full_size(img, h, w), full_size(pair, h, w))})
    clean = next((r for r in rows if r["full"] and r["ref"] >= CLEAN_DB), None)
    drags = [d for r in runs for d in r["drag"]]
    rests = [r["rest"] for r in runs if r["rest"] is not None]
    first = statistics.median(r["images"][0][0] for r in runs[:TIME_RUNS])
    done = statistics.median(r["images"][-1][0] for r in runs[:TIME_RUNS])
    return {"scene": name, "who": f"styletrace {style}", "first": first,
            "clean": clean, "done": done, "images": rows,
            "drag": statistics.median(drags) if drags else None,
            "drag_max": max(drags) if drags else None,
            "rest": statistics.median(rests) if rests else None,
            "shot": a[-1][2] if clean is None else next(
                img for (_, label, img) in a if label == clean["label"])}


def children(S, name: str, size: int, style: str) -> int:
    """The children per camera sample of the defaults' split (the F12 job its Denoise plans)."""
    from styletrace.blender import f12
    from styletrace.pipeline.resolve import resolve
    scene, st = build(S, name, size, style, 0)
    dg = bpy.context.evaluated_depsgraph_get()
    sc = f12.scene(dg, st)
    # the job carries Denoise: resolve chooses the method, then splits the samples for it
    r = resolve(f12.job(sc, f12.integrator(st), st), scene=sc)
    return int(r.budget.children[0])


# ---- a camera move: the image carried to the new view -----------------------------------------

#: timed camera moves per scene and setting (carried and not), alternating; the camera's pan (m)
MOVE_RUNS, PAN = 5, 0.05


def camera_move_rows(S, name: str, size: int, style: str = "cel") -> list[dict]:
    """Seconds from a camera move (`Viewport.set_sensor`, as view_draw gives a moved view) to the
    first image shown, to the draft and to the first pass's image, with and without the carried
    image (`Viewport.carry`); medians of MOVE_RUNS moves each, alternating, after an untimed
    session and an untimed move of each kind (kernels compiled)."""
    scene, st = build(S, name, size, style, SEEDS[0])
    dg = bpy.context.evaluated_depsgraph_get()
    vp = Viewport()
    cam = scene.camera
    times: dict = {True: [], False: []}
    events: list = []
    vp.on_image = lambda: events.append((time.perf_counter(), vp.session.latest()[1]))
    vp.set_sensor(camera.sensor(dg.scene_eval, st.samples))
    vp.update(dg, st)
    vp.session.join(600)
    for k in range(2 * (MOVE_RUNS + 1)):
        carry = k % 2 == 0
        vp.carry = carry
        cam.location.x += PAN if k % 4 < 2 else -PAN
        sensor = camera.sensor(bpy.context.evaluated_depsgraph_get().scene_eval, st.samples)
        events.clear()
        start = time.perf_counter()
        vp.set_sensor(sensor)
        while not any(label.startswith("pass") for _, label in events) and not vp.session.done:
            time.sleep(0.002)
        vp.session.stop(600)
        if vp.session.error:
            raise SystemExit(f"viewport failed: {vp.session.error}")
        shown = [(t - start, label) for t, label in events]
        if k >= 2:  # the first move of each kind compiles what it needs
            times[carry].append({
                "first": shown[0][0],
                "draft": next(t for t, label in shown if label.startswith("draft")),
                "pass": next(t for t, label in shown if label.startswith("pass"))})
    vp.close()
    return [{"scene": name, "carry": carry,
             **{key: statistics.median(r[key] for r in runs) for key in ("first", "draft", "pass")}}
            for carry, runs in times.items()]


def camera_table(rows: list[dict]) -> str:
    out = ["| scene | after a camera move | first image | draft | first pass |",
           "|---|---|---|---|---|"]
    for r in rows:
        how = "the image before, reprojected" if r["carry"] else "nothing until the draft"
        out.append(f"| {r['scene']} | {how} | {fmt(r['first'])} | {fmt(r['draft'])} | "
                   f"{fmt(r['pass'])} |")
    return "\n".join(out)


def camera_main(args) -> None:
    """The camera-move measurement alone: BENCHMARKS.md's section "interactive_camera"."""
    S = scenes_module()
    addon.register()
    rows = []
    for name in args.scenes.split(","):
        rows.extend(camera_move_rows(S, name, args.size))
        say(camera_table(rows[-2:]))
    body = [
        "## Interactive: a camera move (`benchmarks/interactive.py --camera-move`)",
        "",
        machine_description(),
        "",
        f"{args.size}x{args.size}, cel at the add-on's defaults (Samples 16, Denoise auto), 2 "
        f"threads, kernels compiled; the scene camera pans {PAN} m and the time counts from the "
        f"moved view (`Viewport.set_sensor`). Medians of {MOVE_RUNS} moves per row, the two rows "
        "of a scene alternating. With the carried image the first image is the image before, "
        "reprojected to the new view at the draft's size (`blender/viewport_carry.py`); without "
        "it the first image is the draft. " + (args.note or ""),
        "",
        camera_table(rows),
    ]
    say("\n".join(body))
    if not args.no_write:
        write_section("interactive_camera", "\n".join(body))


# ---- Cycles ----------------------------------------------------------------------------------

def cycles_setup(S, name: str, size: int, samples: int, seed: int, converged: bool = False):
    S.SCENES[name](size)
    scene = bpy.context.scene
    scene.render.engine = "CYCLES"
    c = scene.cycles
    c.device, c.samples, c.seed = "CPU", samples, seed
    c.use_adaptive_sampling = True
    c.adaptive_threshold = 0.01 if converged else c.preview_adaptive_threshold
    c.use_denoising = True
    c.denoiser = "OPENIMAGEDENOISE"
    c.denoising_input_passes = "RGB_ALBEDO" if not converged else c.denoising_input_passes
    c.denoising_prefilter = c.preview_denoising_prefilter if not converged else "ACCURATE"
    c.denoising_quality = c.preview_denoising_quality if not converged else "HIGH"
    return scene


def cycles_render(S, name: str, size: int, samples: int, seed: int, tmp: str,
                  converged: bool = False) -> tuple[float, np.ndarray]:
    cycles_setup(S, name, size, samples, seed, converged)
    path = os.path.join(tmp, f"cycles-{name}-{samples}-{seed}.exr")
    start = time.perf_counter()
    img = S.f12(path)["Combined"][..., :3]
    return time.perf_counter() - start, img


def cycles_row(S, name: str, size: int, tmp: str) -> dict:
    _, ref = cycles_render(S, name, size, 1024, REF_SEED, tmp, converged=True)
    rows, clean = [], None
    for k in CYCLES_SAMPLES:
        (ta, a), (tb, b) = (cycles_render(S, name, size, k, seed, tmp) for seed in SEEDS)
        row = {"t": (ta + tb) / 2, "label": f"{k} samples", "full": True, "ref": psnr(a, ref),
               "seeds": measures.noise_psnr(a, b), "image": a}
        rows.append(row)
        say(name, "Cycles", row["label"], f"{row['t']:.2f} s", f"{row['ref']:.1f} dB")
        if row["ref"] >= CLEAN_DB:
            clean = row
            break
    done, _ = cycles_render(S, name, size, 1024, SEEDS[0], tmp)
    return {"scene": name, "who": "Cycles (viewport settings, OIDN)", "first": rows[0]["t"],
            "clean": clean, "done": done, "images": rows, "drag": None, "drag_max": None,
            "rest": None, "shot": (clean or rows[-1])["image"]}


# ---- cost: a stylized render against identity at equal Samples ------------------------------

COST_STYLES = ("identity", "cel", "hatching", "color_map")
COST_RUNS = 3


def median_time(fn, runs: int = COST_RUNS) -> float:
    """Median seconds of `runs` calls of `fn` after one untimed call (kernels compiled)."""
    fn()
    times = []
    for _ in range(runs):
        start = time.perf_counter()
        fn()
        times.append(time.perf_counter() - start)
    return statistics.median(times)


def cost_rows(S, name: str, size: int, tmp: str) -> dict:
    """Seconds of each COST_STYLES render at the defaults (Samples 16, Denoise auto) through F12,
    the command line (`styletrace render` of the scene exported to XML, a fresh process each),
    Python (`styletrace.render` of that file, in this process) and the preview (its session, to
    its last image)."""
    import subprocess

    import styletrace
    out: dict = {}
    exe = os.path.join(ROOT, ".venv", "bin", "styletrace")
    xml = os.path.join(tmp, f"{name}.xml")
    build(S, name, size, "identity", 0)
    bpy.ops.styletrace.export_xml(filepath=xml)
    for style in COST_STYLES:
        build(S, name, size, style, 0)
        path = os.path.join(tmp, f"cost-{name}-{style}.exr")
        out[("F12", style)] = median_time(lambda: S.f12(path))
        command = [exe, "render", xml, "--style", style, "-o", os.path.join(tmp, "cli.exr")]

        def cli():
            done = subprocess.run(command, capture_output=True, text=True)
            if done.returncode:
                raise SystemExit(f"styletrace render failed: {done.stderr.strip()}")
        out[("command line", style)] = median_time(cli)
        out[("Python", style)] = median_time(lambda: styletrace.render(xml, style=style))
        out[("preview", style)] = median_time(lambda: preview_final(xml, style))
        say(name, style, {k[0]: f"{v:.2f} s" for k, v in out.items() if k[1] == style})
    return out


#: seconds between the preview page's polls of the session's state (preview/page.html)
PAGE_POLL_S = 0.3


def preview_final(xml: str, style: str) -> float:
    """Seconds from the preview session's start to its last image (`styletrace preview` at the
    defaults, the page's starting style `style`; no server). The page is played as it behaves: it
    polls every PAGE_POLL_S and restyles each new image, unwaiting."""
    from styletrace.preview.jobs import page_job
    from styletrace.preview.session import Session
    s = Session(page_job(xml, style=style)).start()
    seen = None
    while not s.done and s.error is None:
        time.sleep(PAGE_POLL_S)
        if s.current is not None and s.current is not seen:
            seen = s.current
            s.styled(style, None, {}, wait=False)
    s.stop()
    if s.error is not None:
        raise SystemExit(f"preview failed: {s.error}")
    return s.stats["final_s"]


def cost_table(costs: dict, rows: list[dict]) -> str:
    """Cost against identity per scene, front end and style; the viewport's from its timelines
    (seconds to its last image)."""
    done = {(r["scene"], r["who"].split()[-1]): r["done"] for r in rows
            if r["who"].startswith("styletrace")}
    fronts = ("F12", "command line", "Python", "preview")
    out = ["| scene | front end | identity s | " + " | ".join(
        f"{s} s (x identity)" for s in COST_STYLES[1:]) + " |",
           "|---|---|---|" + "---|" * (len(COST_STYLES) - 1)]
    for scene, c in costs.items():
        for front in fronts:
            base = c[(front, "identity")]
            out.append(f"| {scene} | {front} | {base:.2f} | " + " | ".join(
                f"{c[(front, s)]:.2f} ({c[(front, s)] / base:.2f}x)" for s in COST_STYLES[1:])
                + " |")
        if (scene, "identity") in done and (scene, "cel") in done:
            base = done[(scene, "identity")]
            cel = done[(scene, "cel")]
            out.append(f"| {scene} | viewport, to its last image | {base:.2f} | "
                       f"{cel:.2f} ({cel / base:.2f}x) |" + " - |" * (len(COST_STYLES) - 2))
    return "\n".join(out)


# ---- the report ------------------------------------------------------------------------------

def fmt(x, unit="s", digits=2) -> str:
    return "-" if x is None else f"{x:.{digits}f} {unit}".strip()


def table(rows: list[dict]) -> str:
    out = ["| scene | renderer | first image | clean (>= 30 dB vs converged) | noise at clean "
           "(PSNR between seeds) | done | drag, per value (median, max) | at rest |",
           "|---|---|---|---|---|---|---|---|"]
    for r in rows:
        c = r["clean"]
        drag = ("-" if r["drag"] is None else
                f"{r['drag'] * 1000:.0f} ms, {r['drag_max'] * 1000:.0f} ms")
        out.append(
            f"| {r['scene']} | {r['who']} | {fmt(r['first'])} | "
            f"{'not reached' if c is None else fmt(c['t']) + ' (' + c['label'] + ')'} | "
            f"{'-' if c is None else fmt(c['seeds'], 'dB', 1)} | {fmt(r['done'])} | "
            f"{drag} | {'-' if r['rest'] is None else format(r['rest'] * 1000, '.0f') + ' ms'} |")
    return "\n".join(out)


def timelines(rows: list[dict]) -> str:
    out = []
    for r in rows:
        steps = ", ".join(f"{i['t']:.2f} s {i['label']}: {i['ref']:.1f} dB" for i in r["images"])
        out.append(f"- {r['scene']}, {r['who']}: {steps}")
    return "\n".join(out)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--size", type=int, default=512)
    ap.add_argument("--scenes", default="interior,room,glossy")
    ap.add_argument("--styles", default="identity,cel")
    ap.add_argument("--no-write", action="store_true")
    ap.add_argument("--no-cycles", action="store_true", help="leave Cycles out (a quick run)")
    ap.add_argument("--no-cost", action="store_true", help="leave the cost table out")
    ap.add_argument("--camera-move", action="store_true",
                    help="only the time to the images after a camera move, with and without the "
                         "carried image (section interactive_camera)")
    ap.add_argument("--note", default="", help="a sentence added to the camera-move section")
    args = ap.parse_args()
    if args.camera_move:
        camera_main(args)
        return
    S = scenes_module()
    addon.register()
    rows, costs = [], {}
    with tempfile.TemporaryDirectory() as tmp:
        for name in args.scenes.split(","):
            for style in args.styles.split(","):
                rows.append(styletrace_row(S, name, args.size, style, tmp))
                say(table(rows[-1:]))
            if not args.no_cycles:
                rows.append(cycles_row(S, name, args.size, tmp))
                say(table(rows[-1:]))
            if not args.no_cost:
                costs[name] = cost_rows(S, name, args.size, tmp)
    body = [
        "## Interactive: the viewport against Cycles' (`benchmarks/interactive.py`)",
        "",
        machine_description(),
        "",
        f"{args.size}x{args.size}, 2 threads, kernels cached; the time counts from the edit (an "
        "object moved). The script's docstring defines every column; Cycles' viewport is "
        "measured as F12 renders at its viewport settings (its windowed Blender here has no "
        "OIDN).",
        "",
        table(rows),
        "",
        "Each image shown, with its PSNR against the converged render of the same look:",
        "",
        timelines(rows),
        "",
        "Cost at equal Samples (16, the add-on's default; Denoise auto): seconds per render, "
        f"median of {COST_RUNS} after one untimed run, against the identity style's:",
        "",
        cost_table(costs, rows),
    ]
    say("\n".join(body))
    if not args.no_write:
        write_section("interactive", "\n".join(body))
        # a row per scene, its renderers side by side
        scenes = list(dict.fromkeys(r["scene"] for r in rows))
        panels = [(name, [(r["who"], r["shot"]) for r in rows if r["scene"] == name])
                  for name in scenes]
        image_grid(panels, os.path.join(ROOT, "docs", "interactive.png"))


if __name__ == "__main__":
    main()
