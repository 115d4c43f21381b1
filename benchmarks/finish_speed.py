"""The denoised-expectation finisher's steps timed (issue 36): prints a table, writes no report.

    .venv/bin/python benchmarks/finish_speed.py cornell-box --spp 1 --inner 8
    .venv/bin/python benchmarks/finish_speed.py scene.xml --spp 4 --inner 16 --runs 5
    .venv/bin/python benchmarks/finish_speed.py cornell-box --save out.npz   # images to compare

A render as `styletrace render SCENE --style cel --denoise expectation` makes it (the pipeline's
job, resolved and planned, `denoise.finishers.plan`), 512x512 by default, one pass of all
camera samples. The first run compiles and caches the kernels and is not counted; each of `--runs`
runs after it is timed, and every step's median over them is printed: wall seconds, and the
passes' and the finish's CPU seconds of all threads (less sensitive to a shared machine). Steps
are timed by wrapping the module functions that do them (those that exist in the code measured:
the names changed in issue 36), so a step's time includes the Dr.Jit kernels its results force.
Then the viewport's calls, where the code has them: previews, restyles of the finished buffer and
of its one-point-per-pixel view. The machine is shared: give medians of several runs, and the load
average (printed).
"""
from __future__ import annotations

import argparse
import functools
import os
import statistics
import time
from collections import defaultdict

import numpy as np

import styletrace

styletrace.init()

from styletrace.denoise import coverage as C  # noqa: E402
from styletrace.denoise import expectation as X  # noqa: E402
from styletrace.denoise import oidn  # noqa: E402
from styletrace.denoise.finishers import plan  # noqa: E402
from styletrace.kernel import guides  # noqa: E402
from styletrace.lookdev import buffer as B  # noqa: E402
from styletrace.lookdev import record as R  # noqa: E402
from styletrace.lookdev import restyle as RS  # noqa: E402
from styletrace.pipeline.denoising import Denoising  # noqa: E402
from styletrace.pipeline.job import python_job  # noqa: E402

#: (label, module, function name): wrapped where the module has the name
STEPS = [
    ("record: _pass_arrays (lanes to host)", R, "_pass_arrays"),
    ("record: to_film", R, "to_film"),
    ("record: Buffer.append", B.Buffer, "append"),
    ("attach", X, "attach"),
    ("  guides", guides, "first_hit"),
    ("  own_surface", X, "own_surface"),
    ("  own albedo and emission (device)", X, "_own_device"),
    ("  M (expectation)", X, "expectation"),
    ("  M (expectation)", X, "_expectation"),
    ("  the samples' reflected parts", X, "_reflected"),
    ("  OIDN", oidn, "denoise_oidn"),
    ("  below_resolution", X, "below_resolution"),
    ("  spread", X, "spread"),
    ("  spread", X, "_spread"),
    ("  coverage points", C, "points"),
    ("image_of", X, "image_of"),
]

TIMES: dict[str, list[float]] = defaultdict(list)
_RUN: dict[str, float] = defaultdict(float)
#: inside `coverage.points`: the recording steps are the points' ("coverage: record: ...")
_INSIDE = {"points": 0}


def _wrap(label, owner, name):
    fn = getattr(owner, name, None)
    if fn is None:
        return

    @functools.wraps(fn)
    def timed(*a, **k):
        t = time.perf_counter()
        inside = name == "points"
        _INSIDE["points"] += inside
        try:
            return fn(*a, **k)
        finally:
            _INSIDE["points"] -= inside
            where = ("    coverage: " + label) if _INSIDE["points"] and label.startswith("record") \
                else label
            _RUN[where] += time.perf_counter() - t
    setattr(owner, name, timed)
    # modules that imported the name itself
    for mod in (X, C, R, RS):
        if mod is not owner and getattr(mod, name, None) is fn:
            setattr(mod, name, timed)


def run(scene, args):
    job = python_job(scene, style=args.style, spp=args.spp, inner=args.inner, seed=0,
                     width=args.size, height=args.size, pass_spp=args.spp,
                     denoising=Denoising("expectation", quality=args.quality))
    runner = plan(job)
    fin = runner.finisher
    _RUN.clear()
    t0 = time.perf_counter()
    orig = fin._finish
    box = {}

    c0 = time.process_time()

    def finish():
        box["start"], box["cpu start"] = time.perf_counter(), time.process_time()
        out = orig()
        box["end"], box["cpu end"] = time.perf_counter(), time.process_time()
        return out
    fin._finish = finish
    image = runner.result()
    t1 = time.perf_counter()
    out = dict(_RUN)
    out["total (resolve, passes, finish)"] = t1 - t0
    out["passes (resolve, record)"] = box["start"] - t0
    out["finish"] = box["end"] - box["start"]
    # CPU seconds of every thread (Dr.Jit's workers, OIDN's): less sensitive to a shared machine
    out["passes, CPU s"] = box["cpu start"] - c0
    out["finish, CPU s"] = box["cpu end"] - box["cpu start"]
    buf = fin.job.buffer
    return out, image, buf, fin


def _median_ms(fn, runs: int = 7) -> str:
    fn()  # the first: kernels traced and compiled
    times = []
    for _ in range(runs):
        t = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t)
    return f"{statistics.median(times) * 1e3:8.1f} ms (min {min(times) * 1e3:.1f})"


def extras(job):
    """The viewport's calls where the code has them: previews, restyles of the finished buffer."""
    _, cov = job.finish()
    rows = [("restyle of the finished buffer (cel)", lambda: RS.restyle(cov), 3)]
    if hasattr(job, "preview"):
        rows += [(f"preview({k}, {q!r})", lambda k=k, q=q: job.preview(k, q), 3)
                 for k, q in ((1, "fast"), (0, "fast"), (1, "balanced"))]
    if hasattr(RS, "per_pixel"):
        view = RS.per_pixel(cov)
        rows += [(f"restyle of per_pixel(buffer) ({style})",
                  lambda style=style: RS.restyle(view, style=style), 7)
                 for style in ("cel", "hatching", "color_map")]
    for label, fn, runs in rows:
        print(f"  {label:<42} {_median_ms(fn, runs)}")


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("scene")
    ap.add_argument("--style", default="cel")
    ap.add_argument("--spp", type=int, default=4)
    ap.add_argument("--inner", type=int, default=16)
    ap.add_argument("--size", type=int, default=512)
    ap.add_argument("--quality", default="high")
    ap.add_argument("--runs", type=int, default=3)
    ap.add_argument("--save", help="an .npz for the image, the buffer's arrays and a restyle")
    args = ap.parse_args()
    for step in STEPS:
        _wrap(*step)
    run(args.scene, args)  # compiles and caches the kernels
    for _ in range(args.runs):
        times, image, buf, fin = run(args.scene, args)
        for k, v in times.items():
            TIMES[k].append(v)
    print(f"{args.scene} {args.size}x{args.size} spp {args.spp} n {args.inner} {args.style}, "
          f"median of {args.runs} (load {os.getloadavg()[0]:.2f})")
    order = ["total (resolve, passes, finish)", "passes (resolve, record)", "finish",
             "passes, CPU s", "finish, CPU s"]
    for label, _, _ in STEPS:
        order += [x for x in (label, "    coverage: " + label) if x not in order]
    for i in range(len(TIMES["finish"])):  # what the finish spends besides OIDN
        TIMES["attach less OIDN"].append(TIMES["attach"][i] - TIMES["  OIDN"][i])
    order.insert(order.index("  guides"), "attach less OIDN")
    for k in order:
        if k in TIMES:
            v = TIMES[k]
            print(f"  {k:<42} {statistics.median(v):7.3f} s  ({', '.join(f'{x:.3f}' for x in v)})")
    extras(fin.job)
    if args.save:
        cover = fin.job.buffer  # the noisy buffer; the finisher's result is the coverage buffer
        _, cov = fin.job.finish()
        t = time.perf_counter()
        hatch = RS.restyle(cov, style="hatching")
        print(f"  restyle of the coverage buffer (hatching) {time.perf_counter() - t:.3f} s")
        arrays = {f"cov_{k}": np.asarray(v) for k, v in cov.arrays.items()}
        np.savez(args.save, image=image, hatching=hatch,
                 noisy=np.asarray(cover.image), **arrays)
        print(f"  saved {args.save}")
    del buf


if __name__ == "__main__":
    main()
