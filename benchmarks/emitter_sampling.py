"""Emitter selection for next-event estimation: uniform, power-proportional and spatial (power,
distance and orientation per shading point), at equal time.

For each scene, the identity style (one path per camera sample, inner=1) renders RUNS seeded images
per mode at SPP; the error is the mean squared error against Mitsuba's `path` at REF_SPP (seeded).
The reference's own noise (column ref var: the variance of its mean over 16 seeded parts) adds
alike to every mode's error and is taken off it in the ratios. All modes are unbiased, so the error
falls as 1/time: MSE x seconds (lower is better) compares them at equal time; the last columns are
power's and spatial's over uniform's.
Seconds are the median wall time of a render, as in the first version of this table (the process's
CPU time with --cpu-time, for a machine other work shares; printed only).

Scenes: the three of the first table and a furnished room with 32 lamps (lamp_scenes.lamp_room),
none of which spatial selection's one tuned constant (`spatial_selection.DEFENSIVE`) was chosen on:
that was the corridor (lamp_scenes.lamp_corridor, `--tune`).

    .venv/bin/python benchmarks/emitter_sampling.py            # the table, into BENCHMARKS.md
    .venv/bin/python benchmarks/emitter_sampling.py --print    # the table, printed only
    .venv/bin/python benchmarks/emitter_sampling.py --tune     # DEFENSIVE on the corridor
    .venv/bin/python benchmarks/emitter_sampling.py --cpu-time # CPU seconds, printed only
"""
from __future__ import annotations

import argparse
import os
import statistics
import sys
import time

import numpy as np
from _report import machine_description, write_section
from lamp_scenes import lamp_corridor, lamp_room

import styletrace
from styletrace.frontends.api import load_scene, make_integrator
from styletrace.gate import mi
from styletrace.kernel import spatial_selection

styletrace.init()

#: the modes compared (`auto` is one of them per scene: spatial with the owen_sobol sampler and
#: several lights, else uniform)
COMPARED = ("uniform", "power", "spatial")

RES, SPP, RUNS, REF_SPP = 64, 64, 6, 16384
#: DEFENSIVE values `--tune` compares
TUNE = (0.0, 0.05, 0.1, 0.2, 0.4)


def render(scene, integrator, spp, seed):
    return np.asarray(mi.render(scene, integrator=integrator, spp=spp, seed=seed), dtype=np.float64)


def reference(scene, ref_spp, hide=False):
    """Mitsuba's `path` at ref_spp as 16 seeded parts: (their mean, the variance of that mean
    averaged over the pixel channels); hide: camera rays do not see emitters."""
    path = mi.load_dict({"type": "path", "hide_emitters": hide})
    parts = np.stack([render(scene, path, ref_spp // 16, 10_000 + k) for k in range(16)])
    return parts.mean(axis=0), float(np.mean(parts.var(axis=0, ddof=1)) / len(parts))


#: what a render's seconds are: wall time (an idle machine), or with --cpu-time the process's CPU
#: time over all threads (steadier where other work shares the cores)
CLOCK = time.perf_counter


def measure(scene, ref, mode, spp=SPP, runs=RUNS, hide=False):
    """(mean MSE against ref over `runs` seeds, median seconds per render by CLOCK) for one mode;
    hide: camera rays do not see emitters."""
    integrator = make_integrator("identity", inner=1, emitter_sampling=mode, hide_emitters=hide)
    render(scene, integrator, spp, 99)  # compile
    errs, times = [], []
    for k in range(runs):
        t = CLOCK()
        img = render(scene, integrator, spp, k)
        times.append(CLOCK() - t)
        errs.append(float(np.mean((img - ref) ** 2)))
    return statistics.mean(errs), statistics.median(times)


def scenes(res):
    """{name: (scene, whether camera rays skip emitters)}: the lamp room hides its lamps, whose
    pixels' noise (a small panel hundreds of times brighter than the walls partly covering a
    pixel) no light selection touches."""
    sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "tests"))
    from kernel.test_identity import two_lights
    return {"two lights (400x power ratio)": (mi.load_dict(two_lights(res)), False),
            "dragon (two area lights, sky)": (load_scene("dragon", res, res), False),
            "cornell-box (one light)": (load_scene("cornell-box", res, res), False),
            "room (24 panels, 8 bulbs; lamps hidden)": (mi.load_dict(lamp_room(res)), True)}


def table(res, spp, runs, ref_spp):
    rows = []
    for name, (scene, hide) in scenes(res).items():
        ref, ref_var = reference(scene, ref_spp, hide)
        res_ = {mode: measure(scene, ref, mode, spp, runs, hide) for mode in COMPARED}
        cost = {m: max(mse - ref_var, 0.0) * s for m, (mse, s) in res_.items()}
        cells = " | ".join(f"{res_[m][0]:.3e} | {res_[m][1]:.2f}" for m in COMPARED)
        ratios = " | ".join(f"{cost[m] / cost['uniform']:.2f}" if cost["uniform"] > 0 else "n/a"
                            for m in ("power", "spatial"))
        rows.append(f"| {name} | {ref_var:.1e} | {cells} | {ratios} |")
        print(rows[-1], flush=True)
    return rows


def tune(res, spp, runs, ref_spp):
    """MSE x seconds of spatial selection on the corridor for each DEFENSIVE in TUNE."""
    scene = mi.load_dict(lamp_corridor(res))
    ref, ref_var = reference(scene, ref_spp, True)
    mse, s = measure(scene, ref, "uniform", spp, runs, True)
    base = max(mse - ref_var, 0.0) * s
    print(f"corridor: reference variance {ref_var:.1e}; uniform MSE {mse:.3e}, {s:.2f} s")
    for value in TUNE:
        spatial_selection.DEFENSIVE = value
        mse, s = measure(scene, ref, "spatial", spp, runs, True)
        print(f"DEFENSIVE {value}: MSE {mse:.3e}, {s:.2f} s, (MSE x s) over uniform "
              f"{max(mse - ref_var, 0.0) * s / base:.2f}", flush=True)


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--print", action="store_true", help="print the table, leave "
                        "BENCHMARKS.md alone")
    parser.add_argument("--tune", action="store_true", help="compare DEFENSIVE values on the "
                        "corridor (printed only)")
    parser.add_argument("--res", type=int, default=RES)
    parser.add_argument("--spp", type=int, default=SPP)
    parser.add_argument("--runs", type=int, default=RUNS)
    parser.add_argument("--ref-spp", type=int, default=REF_SPP)
    parser.add_argument("--cpu-time", action="store_true", help="time renders by the process's "
                        "CPU time (a loaded machine; implies --print)")
    args = parser.parse_args()
    if args.cpu_time:
        global CLOCK
        CLOCK, args.print = time.process_time, True
    if args.tune:
        tune(args.res, args.spp, args.runs, args.ref_spp)
        return
    rows = table(args.res, args.spp, args.runs, args.ref_spp)
    if args.print:
        return
    body = "\n".join(
        [
            "## Emitter selection: uniform, power, spatial (`benchmarks/emitter_sampling.py`)",
            "",
            f"Identity style, inner=1, {args.res}x{args.res}, {args.spp} spp, mean over "
            f"{args.runs} seeds; reference: Mitsuba `path` at {args.ref_spp} spp in 16 seeded "
            "parts (ref var: the variance of their mean, taken off every MSE in the ratios). "
            "Last columns: equal-time error of power and spatial over uniform (below 1: better "
            "than uniform). Spatial selection's constant was chosen on another scene (the "
            "corridor, `--tune`).",
            "",
            "| scene | ref var | MSE uniform | s | MSE power | s | MSE spatial | s "
            "| (MSE x s) power / uniform | (MSE x s) spatial / uniform |",
            "|---|---|---|---|---|---|---|---|---|---|",
            *rows,
            "",
            machine_description(),
        ]
    )
    write_section("emitter_sampling", body)


if __name__ == "__main__":
    main()
