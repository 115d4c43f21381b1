"""Speed in Blender: F12 against Cycles, the engine against `styletrace render`, and the export.

Run with the Blender venv (bpy as a module):

    .venv-blender/bin/python benchmarks/blender_speed.py [--size 128] [--runs 3]

Scenes are tests/blender/scenes.py's (room: diffuse; glossy: a glossy sphere; textured_plane).
- Equal noise (identity against Cycles): each renderer renders seeds 1 and 2 at the same samples
  per pixel; the noise of one render is mean((a - b)^2) / 2 over pixels and channels; with noise
  proportional to 1 / spp, time x noise is constant, and the ratio of these products is the ratio of
  the times each needs for the same noise. Cycles as tests/blender/test_cycles.py sets it up (CPU,
  2 threads, no denoising or adaptive sampling, no clamping, box filter), styletrace at denoise off.
- Defaults: F12 with every style at the render settings' defaults (denoise auto, firefly auto), and
  Cycles at its factory defaults (adaptive sampling, OIDN denoising), each on the room.
- Engine against the command line: the scene exported by File > Export (blender/xml.py) and
  rendered by `styletrace render FILE --samples S --spp N --seed K --pass-spp P` (the export
  operator's own command line) in a fresh process, against F12 of the same settings: F12's export
  (depsgraph to a loaded scene) and render timed apart; the command's wall time includes its
  process start.
- Export of a 1-million-triangle mesh (a 707 x 707 grid: 999,698 triangles): the depsgraph to a
  scene description, then to a loaded Mitsuba scene.
Times are medians over --runs after one untimed run (kernel compilation).
"""
from __future__ import annotations

import argparse
import os
import statistics
import subprocess
import sys
import tempfile
import time

import bpy
import numpy as np
from _report import machine_description, write_section

import styletrace.blender as addon
from styletrace.blender import build, engine, exporter, f12
from styletrace.blender.operators import command_line

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)
STYLES = ("identity", "cel", "hatching", "halftone", "color_map")


def scenes_module():
    """tests/blender/scenes.py: the scenes live with their tests."""
    sys.path.insert(0, os.path.join(ROOT, "tests", "blender"))
    import scenes

    return scenes


def timed(fn, runs: int, warm: bool = True) -> tuple[float, object]:
    """(median seconds over `runs` calls, the last call's result); `warm`: after one untimed call
    (styletrace's kernels compiled; Cycles compiles nothing at run time)."""
    out = fn() if warm else None
    times = []
    for _ in range(runs):
        start = time.perf_counter()
        out = fn()
        times.append(time.perf_counter() - start)
    return statistics.median(times), out


def noise(a: np.ndarray, b: np.ndarray) -> float:
    """The variance of one render, from two with different seeds."""
    return float(np.mean((a - b) ** 2) / 2)


def equal_noise(S, name: str, size: int, spp: int, runs: int, tmp: str) -> dict:
    """Identity F12 and Cycles at `spp` on scene `name`: times, noise, and time ratio at equal
    noise (styletrace over Cycles: below 1, styletrace is faster)."""
    row = {"scene": name, "spp": spp}
    for who in ("cycles", "styletrace"):
        images, times = [], []
        for seed in (1, 2):
            S.SCENES[name](size)
            path = os.path.join(tmp, f"{who}-{seed}.exr")
            if who == "cycles":
                t, img = timed(lambda: S.cycles(path, spp, seed=seed), runs, warm=False)
            else:
                t, out = timed(lambda: S.styletrace(path, spp, seed=seed, pass_spp=spp,
                                                    style="identity", denoise="off",
                                                    aovs=False), runs)
                img = out["Combined"][..., :3]
            images.append(img)
            times.append(t)
        row[who] = (statistics.mean(times), noise(*images))
    (tc, vc), (ts, vs) = row["cycles"], row["styletrace"]
    row["ratio"] = (ts * vs) / (tc * vc)
    return row


def defaults(S, size: int, runs: int, tmp: str) -> list[tuple[str, float]]:
    """F12 seconds of every style at its defaults on the room, and Cycles' at its defaults."""
    rows = []
    for style in STYLES:
        S.room(size)
        bpy.context.scene.render.engine = "STYLETRACE"
        st = bpy.context.scene.styletrace
        st.style = style
        path = os.path.join(tmp, f"{style}.exr")
        t, _ = timed(lambda: S.f12(path), runs)
        rows.append((f"styletrace {style}", t))
    S.room(size)
    bpy.context.scene.render.engine = "CYCLES"
    bpy.context.scene.cycles.device = "CPU"
    t, _ = timed(lambda: S.f12(os.path.join(tmp, "cycles.exr")), runs, warm=False)
    rows.append(("Cycles (factory defaults)", t))
    return rows


def engine_against_command(S, size: int, runs: int, tmp: str) -> dict:
    """F12 (export and render apart) against `styletrace render` of the exported XML."""
    S.room(size)
    scene = bpy.context.scene
    scene.render.engine = "STYLETRACE"
    st = scene.styletrace
    # Samples 1024 with 64 camera samples: cel's own 16 children each (the budget, docs/look.md)
    st.style, st.spp, st.pass_spp, st.seed, st.denoise = "cel", 64, 16, 3, "off"
    st.samples = 64 * 16
    path = os.path.join(tmp, "room.xml")
    bpy.ops.styletrace.export_xml(filepath=path)
    command = command_line(path, st).split()
    exe = os.path.join(ROOT, ".venv", "bin", "styletrace")
    out = os.path.join(tmp, "cli.exr")

    def cli():
        done = subprocess.run([exe, *command[1:], "-o", out], capture_output=True, text=True)
        if done.returncode:
            raise SystemExit(f"styletrace render failed: {done.stderr.strip()}")

    t_cli, _ = timed(cli, runs)
    t_f12, _ = timed(lambda: S.f12(os.path.join(tmp, "f12.exr")), runs)
    render = engine.LAST["seconds"]
    return {"f12": t_f12, "render": render, "export": t_f12 - render, "cli": t_cli}


def viewport_times(S, width: int, height: int) -> list[tuple[str, float, float]]:
    """(scene, seconds to the first image, seconds to the last) of the viewport's session at the
    render settings' defaults (cel), seen through the scene camera; each scene is rendered twice
    and the second run is reported (its kernels cached, as after the first edit in a session)."""
    from styletrace.blender import camera
    from styletrace.blender.viewport import Viewport

    rows = []
    for name in ("room", "glossy", "textured_plane"):
        for _ in range(2):
            S.SCENES[name](width)
            scene = bpy.context.scene
            scene.render.resolution_x, scene.render.resolution_y = width, height
            scene.render.engine = "STYLETRACE"
            st = scene.styletrace
            st.style = "cel"
            dg = bpy.context.evaluated_depsgraph_get()
            times, start = [], [0.0]
            vp = Viewport(on_image=lambda: times.append(time.perf_counter() - start[0]))
            vp.set_sensor(camera.sensor(dg.scene_eval, st.samples))
            start[0] = time.perf_counter()
            vp.update(dg, st)
            vp.session.join(600)
            vp.close()
        rows.append((name, times[0], times[-1]))
    return rows


def million_triangles(runs: int) -> dict:
    """Seconds to export a 999,698-triangle grid: to a description, then to a loaded scene."""
    S = scenes_module()
    S.reset(64)
    bpy.ops.mesh.primitive_grid_add(x_subdivisions=708, y_subdivisions=708, size=4.0)
    S.camera((0, -6, 4), S.look((0, -6, 4), (0, 0, 0)))
    S.light("SUN", (0, 0, 5), energy=3.0)
    bpy.context.scene.render.engine = "STYLETRACE"
    depsgraph = bpy.context.evaluated_depsgraph_get()
    st = bpy.context.scene.styletrace
    t_desc, desc = timed(lambda: exporter.export(depsgraph, spp=st.samples), runs)
    t_load, _ = timed(lambda: f12.api.load_scene(build.description_scene_dict(desc)), runs)
    tris = sum(len(p.vertices) - 2 for p in bpy.data.meshes[0].polygons)
    return {"triangles": tris, "describe": t_desc, "load": t_load}


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--size", type=int, default=128)
    ap.add_argument("--runs", type=int, default=3)
    ap.add_argument("--spp", type=int, default=64,
                    help="camera samples per pixel of the equal-noise runs")
    args = ap.parse_args(argv)
    addon.register()
    S = scenes_module()
    lines = []
    with tempfile.TemporaryDirectory() as tmp:
        rows = [equal_noise(S, n, args.size, args.spp, args.runs, tmp)
                for n in ("room", "glossy", "textured_plane")]
        lines += [
            f"Identity at equal noise ({args.size}x{args.size}, {args.spp} spp, seeds 1 and 2; "
            f"median of {args.runs} runs, styletrace's after a warm-up render that compiles its "
            f"kernels):",
            "",
            "| scene | Cycles s | Cycles noise | styletrace s | styletrace noise "
            "| time at equal noise, styletrace / Cycles |",
            "|---|---|---|---|---|---|",
        ]
        for r in rows:
            (tc, vc), (ts, vs) = r["cycles"], r["styletrace"]
            lines.append(f"| {r['scene']} | {tc:.2f} | {vc:.3g} | {ts:.2f} | {vs:.3g} | "
                         f"{r['ratio']:.2f} |")
            print(lines[-1], flush=True)
        lines += ["", f"Defaults on the room ({args.size}x{args.size}), seconds per F12:", "",
                  "| renderer / style | s |", "|---|---|"]
        for label, t in defaults(S, args.size, args.runs, tmp):
            lines.append(f"| {label} | {t:.2f} |")
            print(lines[-1], flush=True)
        e = engine_against_command(S, args.size, args.runs, tmp)
        lines += ["", f"Engine against the command line (room, cel, 64 camera samples of 16 "
                      f"children, passes of 16, "
                      f"{args.size}x{args.size}): F12 {e['f12']:.2f} s = export "
                      f"{e['export']:.2f} s + render {e['render']:.2f} s; `styletrace render` "
                      f"of the exported XML {e['cli']:.2f} s (a fresh process: start-up, scene "
                      f"load and kernel cache look-up included)."]
        print(lines[-1], flush=True)
        v = viewport_times(S, 400, 300)
        lines += ["", "Viewport (Rendered shading) at the defaults with cel, 400x300 through the "
                      "scene camera, kernels cached: seconds to the first image (the draft) and to "
                      "the last pass (clean).", "", "| scene | first image s | clean s |",
                  "|---|---|---|"]
        lines += [f"| {n} | {a:.2f} | {b:.2f} |" for n, a, b in v]
        print("\n".join(lines[-len(v):]), flush=True)
    m = million_triangles(args.runs)
    lines += ["", f"Export of a {m['triangles']:,}-triangle grid: depsgraph to description "
                  f"{m['describe']:.2f} s, description to loaded Mitsuba scene {m['load']:.2f} s."]
    print(lines[-1], flush=True)
    write_section("blender_speed", "## Blender (`benchmarks/blender_speed.py`)\n\n"
                  + machine_description() + "\n\n" + "\n".join(lines))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
