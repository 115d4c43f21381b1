"""Equal-time quality of denoising (issue 21): the expectation denoised before g, the image denoised after it,
reuse, and fixed counts, on three scenes and three styles.

Protocol: `benchmarks/equal_time.py`'s, on more scenes:
- Every render is 1 camera sample per pixel at SIZE x SIZE (128) with seed s, and so is its reference: the same
  seed places the same camera rays, so the error measured is the stylized estimate's. Seeds 0 .. SEEDS-1 (3).
- The reference of seed s is direct application with REF (4096) children per camera sample. It is recorded once
  per (scene, seed) as an expectation buffer and restyled to each style (a restyle equals a fresh render of the
  same seed and n, tests/lookdev/test_restyle.py). Its own error is part of every MSE (it caps the ratios); the
  MSE between a reference of REF/4 children and this one, seed 0, is printed as the order of that floor.
- MSE = bias^2 + variance over the seeds, as equal_time.py: e_s = render_s - reference_s per pixel,
  variance = mean over pixels of var_s(e_s) (ddof 1), bias^2 = mean over pixels of mean_s(e_s)^2 - variance/S
  (an unbiased estimate; it can dip below 0). MSE is the mean over the seeds (= bias^2 + variance).
- Time: the median wall-clock seconds over the seeds, every method of one (scene, style) timed in the same loop,
  interleaved (seed by seed, method by method, after one warm-up render of each), so that the load of the
  shared machine hits all alike. The denoisers' time includes the guides' render and OIDN.
- Equal time: the fixed counts trace the tree sampler's MSE(time) curve; a method is compared with it at its own
  time (log-log interpolation; ≥ / ≤ marks a method outside the curve's time range, as equal_time.py).
- Settings of the expectation denoiser (its n) and of image denoising are chosen on the Cornell box only (the
  n with the best ratio, averaged over cel and hatching); the dragon and the textured floor with a mirror are
  held out: their rows for the chosen n are the verdict, the other n's rows are shown for what they are.
- Reuse: the README's best configuration per style (BENCHMARKS.md, equal_time), re-measured on every scene.

    python benchmarks/denoise.py [--size 128] [--seeds 3] [--scenes cornell-box dragon floor-mirror] [--report]

Results are cached in benchmarks/.cache/denoise_*.npz/json per scene (delete to recompute); `--report` only
writes the BENCHMARKS.md section and docs/denoise.png from the cache.
"""
from __future__ import annotations

import argparse
import json
import os
import statistics
import sys
import time

sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "src"))
sys.path.insert(0, os.path.dirname(__file__))

import styletrace  # noqa: E402

styletrace.init()
import mitsuba as mi  # noqa: E402
import numpy as np  # noqa: E402
from _report import image_grid, machine_description, median_time, write_section  # noqa: E402
from equal_time import envelope, fixed_mse_at  # noqa: E402
from styletrace import api  # noqa: E402
from styletrace.denoise import render as denoised_render  # noqa: E402
from styletrace.lookdev.record import render_buffer  # noqa: E402

CACHE = os.path.join(os.path.dirname(__file__), ".cache")
REF = 4096
SCENES = ("cornell-box", "dragon", "floor-mirror")
HELD_OUT = ("dragon", "floor-mirror")
STYLES = ("cel", "hatching", "color_map")
GOAL = 10.0  # expectation denoising vs the fixed counts at equal time, cel and hatching
FIXED = (4, 8, 16, 32, 64, 128)
# a first run with n = 1, 2, 4 on the Cornell box found the ratio growing with n (the fixed overhead of a render
# and of the denoiser is amortised); the grid goes on from there
EXPECTATION_N = (4, 8, 16, 32)
IMAGE_N = (4, 16, 64)
POOLED = {"reuse": "pixels", "reuse_mis": "pairwise", "reuse_radius": 3, "reuse_k": 48}
# the README's / BENCHMARKS.md's best reuse configuration per style (chosen on the Cornell box there)
REUSE = {"cel": ("reuse m=2:16 K=48 (7x7)", {"inner": "2:16", **POOLED}),
         "hatching": ("reuse m=2:32 K=48 (7x7)", {"inner": "2:32", **POOLED}),
         "color_map": ("reuse m=4 K=48 (7x7)", {"inner": 4, **POOLED})}


READING = (
    "Reading. **The 10x goal is not met on any scene** (best: 3.6x, cel on the Cornell box, where the settings were "
    "chosen; 1.4x to 1.8x on the held-out scenes): a loss. Expectation denoising beats image denoising on hatching "
    "everywhere (image denoising is *worse* than the fixed counts on hatching, 0.5x to 0.8x: it smears the "
    "lines, docs/denoise.png) and on cel on the Cornell box and the dragon, but **loses to it on cel on the "
    "floor-and-mirror scene** (1.66x against 2.01x): a loss. In pictures it is the cleanest of the four columns "
    "(docs/denoise.png), yet by MSE it is not 10x better, for three measured reasons. (1) The reference floor: "
    "a reference of n/4 differs from the n = 4096 one by MSE 3e-3 to 6e-3 for cel and hatching; if a step "
    "style's error falls as 1/sqrt(n), the reference's own error is a third of that, 1e-3 to 2e-3, which is "
    "15-25% of the denoised renders' MSE (7e-3 to 1e-2) and caps any method's ratio at about 10 to 25 at these "
    "times. (2) Sub-pixel placement: the reference's one camera sample per pixel lands on either side of a band "
    "boundary that runs through the pixel; D is a smooth field, so boundary pixels disagree with the reference "
    "seed by seed (this is most of the 'variance' of the denoised rows, whose bias^2 is 1e-3 to 3e-3; the "
    "interpolation of D at each sample's film position removed about a fifth of it, docs/denoise.md). "
    "(3) Overhead: at 128x128 the denoiser's fixed cost (guides, OIDN, interpolation, the buffer's transfer: "
    "0.2 to 0.5 s on the loaded machine) buys the fixed sampler 16 to 32 more children per pixel. Its MSE falls "
    "slowly with n (cel, Cornell box: 1.48e-2 at n = 4, 8.7e-3 at n = 32): what is left is the denoiser's blur "
    "and the boundary placement, not the children's noise. Reuse (`reuse=pixels` with a refinement round, the "
    "README's best configuration) beats expectation denoising at equal time on five of the six (scene, style) "
    "pairs. **Reuse re-measured**: its 4x holds on the Cornell box for hatching (4.95x) but not for cel in this "
    "run (3.12x; 4.02x in the equal_time section, whose fixed grid and timings differ); on the held-out scenes it "
    "does not hold (dragon 1.72x cel, 2.58x hatching; floor and mirror 1.93x, 2.07x). Timing noise: the same "
    "configuration's median time moved by up to 2x between two runs of this script on the shared machine, so "
    "each ratio carries roughly +-40%; the MSE columns are unaffected (the same seeds give the same images). "
    "Disclosure: two rules of the method (albedo 1 for specular first hits, D below the denoiser's resolution set "
    "to 0) were added after seeing the floor-and-mirror images (coloured speckle in the mirror); they change no "
    "MSE on the Cornell box or the dragon (identical to 4 digits before and after), but that scene is not "
    "strictly held out for them. The colour map is not part of the goal; there the three filters reach 1.2x to 3.1x over "
    "the fixed counts, reuse the highest on two of three scenes.")


def floor_mirror(size: int) -> dict:
    """A held-out scene: a checkerboard-textured floor, a mirror, a diffuse sphere, a back wall, one area light."""
    T = mi.ScalarTransform4f
    grey = {"type": "diffuse", "reflectance": {"type": "rgb", "value": [0.6, 0.6, 0.6]}}
    return {
        "type": "scene",
        "sensor": {"type": "perspective", "fov": 45,
                   "to_world": T().look_at(origin=[0, 1.3, 4.5], target=[0, 0.7, 0], up=[0, 1, 0]),
                   "film": {"type": "hdrfilm", "width": size, "height": size, "rfilter": {"type": "box"}},
                   "sampler": {"type": "independent", "sample_count": 1}},
        "floor": {"type": "rectangle", "to_world": T().rotate([1, 0, 0], -90).scale(4),
                  "bsdf": {"type": "diffuse", "reflectance": {
                      "type": "checkerboard", "color0": {"type": "rgb", "value": [0.15, 0.15, 0.2]},
                      "color1": {"type": "rgb", "value": [0.8, 0.75, 0.6]},
                      "to_uv": mi.ScalarTransform4f().scale([8, 8, 1])}}},
        "wall": {"type": "rectangle", "to_world": T().translate([0, 2, -2]).scale(4), "bsdf": grey},
        "mirror": {"type": "rectangle",
                   "to_world": T().translate([-1.1, 0.9, -0.8]).rotate([0, 1, 0], 35).scale([0.7, 0.9, 1]),
                   "bsdf": {"type": "conductor"}},
        "sphere": {"type": "sphere", "center": [0.7, 0.55, 0.1], "radius": 0.55,
                   "bsdf": {"type": "diffuse", "reflectance": {"type": "rgb", "value": [0.7, 0.25, 0.2]}}},
        "light": {"type": "rectangle", "to_world": T().translate([0.3, 3.2, 0.5]).rotate([1, 0, 0], 90).scale(0.6),
                  "emitter": {"type": "area", "radiance": {"type": "rgb", "value": [14, 13, 12]}}},
    }


def load(name: str, size: int) -> mi.Scene:
    return api.load_scene(floor_mirror(size)) if name == "floor-mirror" else api.load_scene(name, size, size)


def methods(style: str) -> list[tuple[str, str, dict]]:
    """(label, kind, keywords): kind "fixed", "expectation", "image" or "reuse"."""
    out = [(f"fixed n={n}", "fixed", {"inner": n}) for n in FIXED]
    out += [(f"denoise expectation n={n}", "expectation", {"inner": n, "denoise": "expectation"})
            for n in EXPECTATION_N]
    out += [(f"denoise image n={n}", "image", {"inner": n, "denoise": "image"}) for n in IMAGE_N]
    label, kw = REUSE[style]
    return out + [(label, "reuse", kw)]


def one(scene, style, kw, seed):
    kw = dict(kw)
    method = kw.pop("denoise", None)
    t = time.perf_counter()
    if method is None:
        img = api.render(scene, style=style, spp=1, seed=seed, **kw)
    else:
        img = denoised_render(scene, style=style, spp=1, seed=seed, denoise=method, **kw)
    return np.asarray(img, dtype=np.float64)[..., :3], time.perf_counter() - t


def references(name, scene, size, seeds):
    """Per seed, {style: reference image}; plus the REF/4 check (seed 0, cel) as an MSE per style."""
    os.makedirs(CACHE, exist_ok=True)
    out = []
    for s in range(seeds):
        path = os.path.join(CACHE, f"denoise_ref_{name}_{size}_{REF}_seed{s}.npz")
        if not os.path.exists(path):
            t = time.perf_counter()
            buf = render_buffer(scene, style="cel", spp=1, inner=REF, seed=s)
            imgs = {st: styletrace.restyle(buf, style=st) for st in STYLES}
            print(f"  reference {name} seed {s}: n={REF}, {time.perf_counter() - t:.0f} s", flush=True)
            np.savez(path, **imgs)
        with np.load(path) as z:
            out.append({st: z[st].astype(np.float64) for st in STYLES})
    path = os.path.join(CACHE, f"denoise_ref_{name}_{size}_{REF // 4}_seed0.npz")
    if not os.path.exists(path):
        buf = render_buffer(scene, style="cel", spp=1, inner=REF // 4, seed=0)
        np.savez(path, **{st: styletrace.restyle(buf, style=st) for st in STYLES})
    with np.load(path) as z:
        check = {st: float(np.mean((z[st] - out[0][st]) ** 2)) for st in STYLES}
    return out, check


def measure_scene(name, size, seeds):
    scene = load(name, size)
    refs, check = references(name, scene, size, seeds)
    results, keep = {}, {}
    for style in STYLES:
        ms = methods(style)
        for label, _, kw in ms:  # warm-up: kernels compiled, caches filled
            one(scene, style, kw, 999)
        imgs = {label: [] for label, _, _ in ms}
        secs = {label: [] for label, _, _ in ms}
        for s in range(seeds):  # interleaved: every method of this comparison under the same load
            for label, _, kw in ms:
                img, t = one(scene, style, kw, s)
                imgs[label].append(img)
                secs[label].append(t)
        for label, kind, _ in ms:
            err = np.stack(imgs[label]) - np.stack([r[style] for r in refs])
            var = float(np.mean(np.var(err, axis=0, ddof=1)))
            bias2 = float(np.mean(err.mean(axis=0) ** 2)) - var / seeds
            mse = float(np.mean(err ** 2))
            results[f"{style}|{label}"] = {"style": style, "method": label, "kind": kind,
                                           "secs": statistics.median(secs[label]), "mse": mse, "bias2": bias2,
                                           "var": var}
            keep[f"{style}|{label}"] = imgs[label][0].astype(np.float32)
            print(f"  {name} {style} {label}: {statistics.median(secs[label]):.2f} s, MSE {mse:.3e} "
                  f"(bias^2 {bias2:.2e}, var {var:.2e})", flush=True)
        keep[f"{style}|reference"] = refs[0][style].astype(np.float32)
    with open(os.path.join(CACHE, f"denoise_results_{name}_{size}.json"), "w") as f:
        json.dump({"results": results, "ref_check": check, "seeds": seeds}, f, indent=1)
    np.savez(os.path.join(CACHE, f"denoise_images_{name}_{size}.npz"), **keep)


def ratios(results: dict, style: str) -> dict[str, tuple[float, str]]:
    rows = [r for r in results.values() if r["style"] == style]
    curve = envelope([(r["secs"], r["mse"]) for r in rows if r["kind"] == "fixed"])
    out = {}
    for r in rows:
        if r["kind"] != "fixed":
            at, mark = fixed_mse_at(curve, r["secs"])
            out[r["method"]] = (at / r["mse"], mark)
    return out


def chosen(cornell: dict, kind: str, ns) -> str:
    """The n of `kind` with the best mean ratio over cel and hatching on the Cornell box."""
    prefix = "denoise expectation" if kind == "expectation" else "denoise image"
    score = {n: np.mean([ratios(cornell, st)[f"{prefix} n={n}"][0] for st in ("cel", "hatching")]) for n in ns}
    return f"{prefix} n={max(score, key=score.get)}"


def report(size):
    data = {}
    for name in SCENES:
        path = os.path.join(CACHE, f"denoise_results_{name}_{size}.json")
        if os.path.exists(path):
            with open(path) as f:
                data[name] = json.load(f)
    if "cornell-box" not in data:
        raise SystemExit("no Cornell box results cached: run the measurement first")
    pick_e = chosen(data["cornell-box"]["results"], "expectation", EXPECTATION_N)
    pick_i = chosen(data["cornell-box"]["results"], "image", IMAGE_N)
    sections, verdicts, panels = [], [], []
    for name, d in data.items():
        res = d["results"]
        held = " (held out)" if name in HELD_OUT else " (settings chosen here)"
        lines = [f"### {name}{held}", "",
                 f"Reference: direct application, n={REF}, seed by seed. A reference of n={REF // 4} differs from it "
                 f"(seed 0) by MSE " + ", ".join(f"{st} {v:.2e}" for st, v in d["ref_check"].items())
                 + ": the order of the floor every MSE below includes.", "",
                 "| style | method | s (median) | MSE | bias^2 | variance | fixed-n MSE at this time / MSE |",
                 "|---|---|---:|---:|---:|---:|---:|"]
        for style in STYLES:
            rat = ratios(res, style)
            for r in res.values():
                if r["style"] != style:
                    continue
                g = "" if r["kind"] == "fixed" else f"{rat[r['method']][1]}{rat[r['method']][0]:.2f}"
                label = f"**{r['method']}**" if r["method"] in (pick_e, pick_i) else r["method"]
                lines.append(f"| {style} | {label} | {r['secs']:.2f} | {r['mse']:.3e} | {r['bias2']:.2e} | "
                             f"{r['var']:.2e} | {g} |")
            if style in ("cel", "hatching"):
                e, i = rat[pick_e][0], rat[pick_i][0]
                reuse = rat[REUSE[style][0]][0]
                ok = e >= GOAL
                verdicts.append(f"| {name} | {style} | {e:.2f}x | {'met' if ok else '**LOSS: not met**'} | {i:.2f}x | "
                                f"{'yes' if e > i else '**no: LOSS**'} | {reuse:.2f}x |")
        sections.append("\n".join(lines))
        imgs = np.load(os.path.join(CACHE, f"denoise_images_{name}_{size}.npz"))
        for style in ("cel", "hatching"):
            t = res[f"{style}|{pick_e}"]["secs"]
            near = min((r for r in res.values() if r["style"] == style and r["kind"] == "fixed"),
                       key=lambda r: abs(np.log(r["secs"] / t)))["method"]
            panels.append((f"{name}, {style}", [
                ("reference", imgs[f"{style}|reference"]),
                (f"{near}, {res[f'{style}|{near}']['secs']:.2f} s", imgs[f"{style}|{near}"]),
                (f"{pick_i}, {res[f'{style}|{pick_i}']['secs']:.2f} s", imgs[f"{style}|{pick_i}"]),
                (f"{pick_e}, {t:.2f} s", imgs[f"{style}|{pick_e}"])]))
    timing_lines = []
    tpath = os.path.join(CACHE, "denoise_timing_512.json")
    if os.path.exists(tpath):
        with open(tpath) as f:
            tm = json.load(f)
        timing_lines = ["### Cost at 512x512", "",
                        "Cornell box, 512x512, 1 camera sample per pixel, n = 8, cel; median of 3 runs, same shared "
                        "2-core machine (`python benchmarks/denoise.py --timing`).", "",
                        "| step | s |", "|---|---:|"] + [f"| {k} | {v:.2f} |" for k, v in tm.items() if k != "size"]
    body = "\n".join([
        "## Denoising at a budget: the expectation before g, the image after it (`benchmarks/denoise.py`)",
        "",
        f"{size}x{size}, 1 camera sample per pixel, seeds 0..{next(iter(data.values()))['seeds'] - 1}, each render "
        "against a reference of the same seed (the same camera rays). Protocol: the script's docstring. The "
        "machine was shared with other jobs while this ran (2 cores, load average above 4): times are noisy, "
        "which is why every method of one (scene, style) was timed interleaved in one loop. Settings of the "
        f"denoisers chosen on the Cornell box alone (expectation: `{pick_e}`, image: `{pick_i}`, in bold); the "
        "dragon and the floor-and-mirror scene are held out. Last column: the fixed counts' MSE at the method's "
        "time over the method's MSE (above 1: better than the tree sampler at equal time; ≥: the method is "
        "faster than every fixed count, so compared with the cheapest; ≤: slower than every fixed count).",
        "",
        f"Goal: expectation denoising ≥ {GOAL:g}x lower MSE than the fixed counts at equal time, cel and hatching, "
        "every scene, and better than image denoising:",
        "",
        "| scene | style | expectation ratio | goal | image-denoising ratio | expectation beats image | reuse ratio |",
        "|---|---|---:|---|---:|---|---:|",
        *verdicts,
        "",
        READING,
        "",
        *sections,
        "",
        *timing_lines,
        "",
        machine_description(),
    ])
    write_section("denoise", body)
    image_grid(panels, os.path.join(os.path.dirname(__file__), "..", "docs", "denoise.png"), row_height=2.75,
               fontsize=7, width=10)


def timing(size: int = 512, runs: int = 3) -> dict:
    """Seconds of the denoising steps at size x size on the Cornell box (1 spp, n = 8), median of `runs`:
    OIDN alone at each quality, the guides' render, the interpolation at the samples, and the whole
    `attach` (guides + OIDN high + interpolation), against the render of the noisy buffer itself."""
    from styletrace.denoise import expectation as X
    from styletrace.denoise import guides, oidn
    scene = load("cornell-box", size)
    integ = api.make_integrator(style="cel", inner=8)

    def med(fn):
        return median_time(fn, runs)

    buf = None

    def record():
        nonlocal buf
        buf = render_buffer(scene, spp=1, seed=0, integrator=integ)
    out = {"size": size, "record (render, n=8, 1 spp)": med(record)}
    m = X.expectation(buf)
    al, nn, pos = guides.first_hit(scene, 1, api.pass_seed(0, 0), position=True)
    out["guides (aov render)"] = med(lambda: guides.first_hit(scene, 1, api.pass_seed(0, 0), position=True))
    for q in ("high", "balanced", "fast"):
        out[f"OIDN {q}"] = med(lambda: oidn.run(m, al, nn, q))
    d = oidn.run(m, al, nn)
    out["interpolation at the samples"] = med(lambda: X.at_samples(buf, d, scene, al, nn, pos))
    out["attach (guides + OIDN high + interpolation)"] = med(lambda: X.attach(buf, scene, 1, 0))
    out["restyle of the denoised buffer"] = med(lambda: styletrace.restyle(buf, style="hatching"))
    with open(os.path.join(CACHE, f"denoise_timing_{size}.json"), "w") as f:
        json.dump(out, f, indent=1)
    return out


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--size", type=int, default=128)
    ap.add_argument("--seeds", type=int, default=3)
    ap.add_argument("--scenes", nargs="*", default=list(SCENES))
    ap.add_argument("--report", action="store_true", help="only write the section and figure from the cache")
    ap.add_argument("--ref", type=int, default=REF, help="the reference's children per camera sample")
    ap.add_argument("--timing", action="store_true", help="only time the denoising steps at 512x512")
    args = ap.parse_args()
    globals()["REF"] = args.ref
    if args.timing:
        os.makedirs(CACHE, exist_ok=True)
        print(json.dumps(timing(), indent=1))
        return
    if not args.report:
        for name in args.scenes:
            print(f"{name}:", flush=True)
            measure_scene(name, args.size, args.seeds)
    report(args.size)


if __name__ == "__main__":
    main()
