"""Low-discrepancy samples: the `owen_sobol` sampler against `independent`, at equal samples and
equal time, on the built-in scenes.

Protocol: each scene at RES x RES, rendered through `api.passes` (denoising off) with the same
integrator, seeds 0 .. SEEDS-1, at SPP camera samples per pixel, with the scene's sampler
`owen_sobol` and `independent` (`load_scene(..., sampler=...)`). Error: the mean squared error
against a reference of REF_SPP independent samples per pixel in two seeded halves, minus the
reference's own noise (a quarter of the halves' mean squared difference). The reference is
Mitsuba's `path` for identity on scenes without styled objects, else the stylized integrator with
the same settings. Time: the median seconds of a render (kernels compiled before). Equal time:
(MSE x s) owen_sobol / independent, below 1 better. `emitter_sampling` `uniform` for both
isolates the sampler; `auto` (identity only) is what a render gets: spatial selection with
`owen_sobol` where the scene has several lights, uniform with `independent` (the same converged
image: identity's estimator is unbiased). Cel's direct application converges to an image that
depends on the children's distribution, so cel and the styled objects of `mixed` are compared
with `uniform` only.

    .venv/bin/python benchmarks/sampler.py [--res 64] [--seeds 4] [--no-write]
"""
from __future__ import annotations

import argparse
import statistics
import time

import numpy as np
from _report import machine_description, write_section

import styletrace
from styletrace.frontends import api
from styletrace.gate import mi

styletrace.init()

SPP = (16, 64, 256)
REF_SPP = 4096
STYLES = {"identity": dict(style="identity", inner_samples=1),
          "cel": dict(style="cel", inner_samples=4, thresholds="0.1,0.3", levels="0.1,0.5,0.9")}


def render(scene, integrator, spp: int, seed: int) -> tuple[np.ndarray, float]:
    """(the image's RGB as float64, seconds)."""
    start = time.perf_counter()
    img = list(api.passes(scene, integrator, spp, seed=seed))[-1].image[..., :3]
    return img.astype(np.float64), time.perf_counter() - start


def reference(name: str, style: str, res: int) -> tuple[np.ndarray, float]:
    """(the mean of two independent references with uniform emitter selection, the squared error
    it has left)."""
    scene = api.load_scene(name, res, res, sampler="independent")
    if style == "identity" and name != "mixed":
        path = mi.load_dict({"type": "path"})
        halves = [np.asarray(mi.render(scene, integrator=path, spp=REF_SPP // 2, seed=9000 + s),
                             np.float64)[..., :3] for s in range(2)]
    else:
        integ = api.make_integrator_from(dict(STYLES[style], emitter_sampling="uniform"))
        halves = [render(scene, integ, REF_SPP // 2, 9000 + s)[0] for s in range(2)]
    left = float(np.mean((halves[0] - halves[1]) ** 2)) / 4
    return (halves[0] + halves[1]) / 2, left


def measure(name: str, style: str, res: int, seeds: int, emitters: str) -> list[dict]:
    ref, left = reference(name, style, res)
    values = dict(STYLES[style], emitter_sampling=emitters)
    out = []
    for spp in SPP:
        row = {"scene": name, "style": style, "spp": spp, "emitters": emitters}
        for sampler in ("owen_sobol", "independent"):
            scene = api.load_scene(name, res, res, sampler=sampler)
            integ = api.make_integrator_from(values)
            render(scene, integ, spp, 100)  # compiles
            runs = [render(scene, integ, spp, s) for s in range(seeds)]
            mse = float(np.mean([np.mean((img - ref) ** 2) for img, _ in runs])) - left
            row[sampler] = (mse, statistics.median(t for _, t in runs))
        out.append(row)
        (mo, to), (mi_, ti) = row["owen_sobol"], row["independent"]
        print(f"{name} {style} {spp} spp ({emitters}): MSE {mo:.3e} vs {mi_:.3e} "
              f"({mo / mi_:.2f}), s {to:.3f} vs {ti:.3f}", flush=True)
    return out


#: (scene, style, emitter_sampling) measured
CASES = (("cornell-box", "identity", "auto"), ("cornell-box", "cel", "uniform"),
         ("dragon", "identity", "auto"), ("dragon", "identity", "uniform"),
         ("dragon", "cel", "uniform"), ("mixed", "identity", "uniform"))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--res", type=int, default=64)
    ap.add_argument("--seeds", type=int, default=4)
    ap.add_argument("--no-write", action="store_true")
    args = ap.parse_args()
    rows = []
    for name, style, emitters in CASES:
        rows += measure(name, style, args.res, args.seeds, emitters)
    lines = []
    for r in rows:
        (mo, to), (mi_, ti) = r["owen_sobol"], r["independent"]
        lines.append(f"| {r['scene']} | {r['style']} | {r['emitters']} | {r['spp']} | {mo:.2e} "
                     f"| {mi_:.2e} | {mo / mi_:.2f} | {to:.3f} | {ti:.3f} | "
                     f"{mo * to / (mi_ * ti):.2f} |")
    body = "\n".join([
        "## Low-discrepancy samples: `owen_sobol` against `independent` (`benchmarks/sampler.py`)",
        "",
        f"{args.res}x{args.res}, denoising off, {args.seeds} seeds; MSE against a reference of "
        f"{REF_SPP} independent samples per pixel with uniform emitter selection (its own noise "
        "taken off; Mitsuba's `path` for identity without styled objects). Cel: 4 children, "
        "thresholds 0.1, 0.3; `mixed` keeps its objects' styles. `emitters`: the integrator's "
        "`emitter_sampling` (auto: spatial with `owen_sobol` where the scene has several lights, "
        "uniform with `independent`; identity only, whose converged image does not depend on "
        "it). Last column: equal-time error, (MSE x s) owen_sobol / independent, below 1 better.",
        "",
        "| scene | style | emitters | spp | MSE owen_sobol | MSE independent | ratio | s owen "
        "| s indep. | equal time |",
        "|---|---|---|---|---|---|---|---|---|---|",
        *lines,
        "",
        machine_description(),
    ])
    if not args.no_write:
        write_section("sampler", body)
    print(body)


if __name__ == "__main__":
    main()
