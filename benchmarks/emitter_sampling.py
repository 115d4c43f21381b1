"""Emitter selection for next-event estimation: uniform against power-proportional, at equal time.

For each scene, the identity style (one path per camera sample, inner=1) renders RUNS seeded images
per mode at SPP; the error is the mean squared error against Mitsuba's `path` at REF_SPP (seeded).
Both modes are unbiased, so MSE falls as 1/time: MSE x seconds (lower is better) compares them at
equal time.

    .venv/bin/python benchmarks/emitter_sampling.py
"""
from __future__ import annotations

import os
import statistics
import sys
import time

import numpy as np
from _report import machine_description, write_section

import styletrace
from styletrace.frontends.api import load_scene, make_integrator
from styletrace.gate import mi
from styletrace.kernel import emitter_sampler

styletrace.init()

RES, SPP, RUNS, REF_SPP = 64, 64, 6, 16384


def render(scene, integrator, spp, seed):
    return np.asarray(mi.render(scene, integrator=integrator, spp=spp, seed=seed), dtype=np.float64)


def reference(scene):
    path = mi.load_dict({"type": "path"})
    return np.mean([render(scene, path, REF_SPP // 16, 10_000 + k) for k in range(16)], axis=0)


def measure(scene, ref, mode):
    integrator = make_integrator("identity", inner=1, emitter_sampling=mode)
    render(scene, integrator, SPP, 99)  # compile
    errs, times = [], []
    for k in range(RUNS):
        t = time.perf_counter()
        img = render(scene, integrator, SPP, k)
        times.append(time.perf_counter() - t)
        errs.append(float(np.mean((img - ref) ** 2)))
    return statistics.mean(errs), statistics.median(times)


def main():
    sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "tests"))
    from kernel.test_identity import two_lights
    scenes = {"two lights (400x power ratio)": mi.load_dict(two_lights(RES)),
              "dragon (two area lights, sky)": load_scene("dragon", RES, RES),
              "cornell-box (one light)": load_scene("cornell-box", RES, RES)}
    rows = []
    for name, scene in scenes.items():
        ref = reference(scene)
        res = {mode: measure(scene, ref, mode) for mode in emitter_sampler.MODES}
        (mu, tu), (mp, tp) = res["uniform"], res["power"]
        rows.append(
            f"| {name} | {mu:.3e} | {tu:.2f} | {mp:.3e} | {tp:.2f} | {(mp * tp) / (mu * tu):.2f} |"
        )
        print(rows[-1], flush=True)
    body = "\n".join(
        [
            "## Emitter selection: uniform vs power (`benchmarks/emitter_sampling.py`)",
            "",
            f"Identity style, inner=1, {RES}x{RES}, {SPP} spp, mean over {RUNS} seeds; reference: "
            f"Mitsuba `path` "
            f"at {REF_SPP} spp. Last column: equal-time error of power over uniform (below 1: "
            f"power wins).",
            "",
            "| scene | MSE uniform | s | MSE power | s | (MSE x s) power / uniform |",
            "|---|---|---|---|---|---|",
            *rows,
            "",
            machine_description(),
        ]
    )
    write_section("emitter_sampling", body)


if __name__ == "__main__":
    main()
