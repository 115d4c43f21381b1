"""Rendering on Ray (`--ray`) against the local path, scaling with workers, and the time to resume.

1. Overhead: cornell-box 256x256, cel, S=64, n=16, as `api.passes` in this process (Dr.Jit on all
   cores) and as Ray tasks on a local instance (one task per core, one Dr.Jit thread each), both
   warm (kernels compiled, workers' scenes loaded), median of `--runs`.
2. Scaling: a local Ray instance of 1, 2 and 4 CPUs, each worker one thread, images per minute of
   cornell-box 128x128, cel, S=16, n=8 split into 8 passes (warm, median of `--runs`).
3. Resume: the same 256x256 render stopped after half its passes, then resumed: the time to read the
   checkpoint and the time to finish, against the whole render.

    .venv/bin/python benchmarks/ray_scaling.py [--runs 3]
"""
from __future__ import annotations

import argparse
import os
import statistics
import tempfile
import time

import ray
from _report import machine_description, median_time, write_section

import styletrace
from styletrace.frontends import api
from styletrace.pipeline.passes import PassSplit
from styletrace.pipeline.ray_checkpoint import Checkpoint, Checkpoints
from styletrace.pipeline.ray_plan import Plan
from styletrace.pipeline.ray_run import Render, job_for

styletrace.init()

SRC = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", "src"))


def start(cpus):
    ray.shutdown()
    t = time.perf_counter()
    ray.init(num_cpus=cpus, include_dashboard=False, logging_level="error", log_to_driver=False)
    return time.perf_counter() - t


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--runs", type=int, default=3)
    args = ap.parse_args()
    os.environ["PYTHONPATH"] = os.pathsep.join(p for p in (SRC, os.environ.get("PYTHONPATH")) if p)
    cores = os.cpu_count()
    style = {"style": "cel", "inner": 16}
    w = h = 256
    spp = 64
    scene = api.load_scene("cornell-box", w, h)
    integ = api.make_integrator(**style)
    job = job_for("cornell-box", integ, w, h)

    def local():
        for _ in api.passes(scene, integ, spp, 0):
            pass

    def on_ray():
        for _ in Render(job, Plan(w, h, spp, 0), "local"):
            pass

    # alternate the two so that load from other processes (a shared machine) falls on both alike
    t_init = start(cores)
    local(), on_ray()  # warm-up: kernels compiled, workers started and their scenes loaded
    t_local, t_ray, loads = [], [], [os.getloadavg()[0]]
    for _ in range(args.runs):
        for fn, out in ((local, t_local), (on_ray, t_ray)):
            t = time.perf_counter()
            fn()
            out.append(time.perf_counter() - t)
        loads.append(os.getloadavg()[0])
    t_local, t_ray = statistics.median(t_local), statistics.median(t_ray)
    units = len(Render(job, Plan(w, h, spp, 0)).units)

    # resume: stop after half the passes, then finish from the checkpoint
    tmp = tempfile.mkdtemp()
    out = os.path.join(tmp, "r.exr")
    by_4 = Plan(w, h, spp, 0, PassSplit(pass_spp=4))
    half = Render(job, by_4, "local", Checkpoints(out, every=3600))
    n_units = len(half.units)
    for i, _ in enumerate(half):
        if i + 1 >= n_units // 2:
            break
    t = time.perf_counter()
    Checkpoint(out, half.checkpoint.settings).load()
    t_read = time.perf_counter() - t
    t = time.perf_counter()
    rest = Render(job, by_4, "local", Checkpoints(out, resume=True))
    for _ in rest:
        pass
    t_rest = time.perf_counter() - t
    rest.finish()
    t = time.perf_counter()
    for _ in Render(job, by_4, "local"):
        pass
    t_whole = time.perf_counter() - t

    # scaling
    sw = sh = 128
    sjob = job_for("cornell-box", api.make_integrator(style="cel", inner=8), sw, sh)
    rows = []
    for workers in (1, 2, 4):
        start(workers)
        secs = median_time(
            lambda: [None for _ in Render(sjob, Plan(sw, sh, 16, 0, PassSplit(pass_spp=2)),
                                          "local")],
            args.runs,
        )
        rows.append((workers, secs, 60.0 / secs))
    ray.shutdown()

    base = rows[0][2]
    table = "\n".join(f"| {wk} | {s:.2f} | {ipm:.1f} | {ipm / base:.2f} |" for wk, s, ipm in rows)
    body = f"""## Rendering on Ray (`benchmarks/ray_scaling.py`)

Machine: {machine_description()}. This machine has **{cores} cores**, shared with other work while \
this ran:
the scaling rows above {cores} workers measure oversubscription, not a cluster.

**Overhead of `--ray` on one machine**, cornell-box 256x256, cel, S=64 camera samples, n=16 inner \
samples
({units} passes of 2^20 samples), warm, median of {args.runs} runs alternating local and Ray \
(1-minute load
average {min(loads):.1f} to {max(loads):.1f} meanwhile): local path (`api.passes`, Dr.Jit on \
{cores} threads)
**{t_local:.2f} s**; Ray tasks on a local instance ({cores} workers of one thread) **{t_ray:.2f} \
s**, ratio
**{t_ray / t_local:.3f}** (goal <= 1.10). Starting the local Ray instance took {t_init:.1f} s \
more, once per
process (not in the ratio); a worker's first task also loads the scene and compiles the kernel \
(Dr.Jit's
kernel cache on disk serves the later workers).

**Scaling**, cornell-box 128x128, cel, S=16, n=8, 8 passes, a local Ray instance of W CPUs, \
workers of one
thread each, warm, median of {args.runs}:

| workers | s per image | images per minute | speed-up |
|---|---|---|---|
{table}

**Resume**, the 256x256 render split into {n_units} passes of 4 spp, stopped after {n_units // 2}: \
reading the
checkpoint (EXR of the running sum + JSON manifest) took {t_read * 1000:.0f} ms; finishing the \
rest took
{t_rest:.2f} s against {t_whole:.2f} s for the whole render from scratch.

**On a real cluster**: on one machine run `ray start --head` (it prints the address, HOST:6379), \
on every
other `ray start --address HOST:6379`; each needs the same styletrace, Mitsuba and Dr.Jit installed
(`pip install 'styletrace[ray]'`) and the scene files at the same absolute paths (or use built-in \
scenes).
Then, anywhere on the cluster: `styletrace render scene.xml --spp 4096 -o out.exr --ray \
HOST:6379`. Each
task asks Ray for one CPU and runs Dr.Jit on one thread; a node of C cores runs C tasks at once.
"""
    write_section("ray_scaling", body)
    print(body)


if __name__ == "__main__":
    main()
