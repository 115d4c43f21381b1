"""Speed and memory of the `stylized` integrator against Mitsuba's own `path`, measured in one run.

For each built-in scene at 256x256: `stylized` at S camera samples with n inner samples per first hit,
timed against `path` at S*n samples per pixel (the same number of light paths; the stylized tree
shares each camera ray and first intersection among its n children). Each configuration is warmed up
once (kernel compilation), then timed `--runs` times; the table gives medians. Peak memory is the
maximum resident set size of a separate process rendering 512x512 at S=64, n=64.

    python benchmarks/render_speed.py [--runs 3] [--skip-memory]
"""
from __future__ import annotations

import argparse
import os
import statistics
import subprocess
import sys
import time

sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "src"))
sys.path.insert(0, os.path.dirname(__file__))

import styletrace  # noqa: E402

styletrace.init()  # first: it points Dr.Jit at a working libLLVM
import mitsuba as mi  # noqa: E402
from styletrace.api import load_scene, make_integrator, passes  # noqa: E402
from _report import machine_description, write_section  # noqa: E402

RES = 256
S, N = 16, 8


def timed(scene, integrator, spp, runs):
    for _ in passes(scene, integrator, spp, seed=99):  # warm-up: compile and cache the kernels
        pass
    times = []
    for r in range(runs):
        t = time.perf_counter()
        for _ in passes(scene, integrator, spp, seed=r):
            pass
        times.append(time.perf_counter() - t)
    return statistics.median(times), times


MEMORY_CODE = """
import resource, sys, time
sys.path.insert(0, {src!r})
import styletrace
t = time.perf_counter()
styletrace.render('cornell-box', style='cel', spp=64, inner=64, width=512, height=512)
print(time.perf_counter() - t, resource.getrusage(resource.RUSAGE_SELF).ru_maxrss)
"""


def peak_memory():
    src = os.path.join(os.path.dirname(__file__), "..", "src")
    out = subprocess.run([sys.executable, "-c", MEMORY_CODE.format(src=os.path.abspath(src))],
                         capture_output=True, text=True, check=True).stdout.split()
    return float(out[0]), int(out[1]) / 1024.0  # seconds, MiB (ru_maxrss is in KiB on Linux)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--runs", type=int, default=3)
    ap.add_argument("--skip-memory", action="store_true")
    args = ap.parse_args()

    rows = []
    for name in ("cornell-box", "dragon"):
        scene = load_scene(name, RES, RES)
        t_path, _ = timed(scene, mi.load_dict({"type": "path"}), S * N, args.runs)
        for style in ("identity", "cel"):
            t_ours, _ = timed(scene, make_integrator(style, inner=N), S, args.runs)
            paths = RES * RES * S * N
            rows.append((name, style, t_ours, t_path, t_ours / t_path, paths / t_ours / 1e6))
        print(rows[-2:], flush=True)

    lines = [
        "## Stylized integrator vs Mitsuba `path` (`benchmarks/render_speed.py`)", "",
        f"Machine: {machine_description()}.", "",
        f"{RES}x{RES}, `stylized` at S={S} camera samples x n={N} inner samples vs `path` at {S * N} spp "
        f"(same number of light paths), max_depth unbounded, Russian roulette from depth 5, median of "
        f"{args.runs} runs after one warm-up run. Targets: identity ratio <= 1.0, cel ratio <= 1.05.", "",
        "| scene | style | stylized (s) | path (s) | ratio | stylized M paths/s |",
        "|---|---|---|---|---|---|",
    ]
    for name, style, t_o, t_p, ratio, rate in rows:
        lines.append(f"| {name} | {style} | {t_o:.2f} | {t_p:.2f} | {ratio:.3f} | {rate:.2f} |")
    if not args.skip_memory:
        secs, mib = peak_memory()
        lines += ["", f"Peak memory (max RSS of a fresh process, Python + Mitsuba + kernels), cornell-box at 512x512, "
                      f"cel, S=64, n=64 ({512 * 512 * 64 * 64 / 1e9:.2f} G light paths): **{mib:.0f} MiB** "
                      f"in {secs:.0f} s. Target <= 1 GB."]
    write_section("render_speed", "\n".join(lines))
    print("\n".join(lines))


if __name__ == "__main__":
    main()
