"""Equal-time quality of denoising (issue 21): the expectation denoised before g, the image denoised
after it, reuse, and fixed counts, on three scenes and three styles.

Protocol: `benchmarks/equal_time.py`'s, on more scenes:
- Every render is 1 camera sample per pixel at SIZE x SIZE (128) with seed s, and so is its
  reference: the same seed places the same camera rays, so the error measured is the stylized
  estimate's. Seeds 0 .. SEEDS-1 (3).
- The reference of seed s is direct application with REF (4096) children per camera sample. It is
  recorded once per (scene, seed) as an expectation buffer and restyled to each style (a restyle
  equals a fresh render of the same seed and n, tests/lookdev/test_restyle.py). Its own error is
  part of every MSE (it caps the ratios); the MSE between a reference of REF/4 children and this
  one, seed 0, is printed as the order of that floor.
- MSE = bias^2 + variance over the seeds, as equal_time.py: e_s = render_s - reference_s per pixel,
  variance = mean over pixels of var_s(e_s) (ddof 1), bias^2 = mean over pixels of mean_s(e_s)^2 -
  variance/S (an unbiased estimate; it can dip below 0). MSE is the mean over the seeds (= bias^2 +
  variance).
- Time: the median wall-clock seconds over the seeds, every method of one (scene, style) timed in
  the same loop, interleaved (seed by seed, method by method, after one warm-up render of each), so
  that the load of the shared machine hits all alike. The denoisers' time includes the guides'
  render and OIDN.
- Equal time: the fixed counts trace the tree sampler's MSE(time) curve; a method is compared with
  it at its own time (log-log interpolation; ≥ / ≤ marks a method outside the curve's time range, as
  equal_time.py).
- Settings of the expectation denoiser (its n) and of image denoising are chosen on the Cornell box
  only (the n with the best ratio, averaged over cel and hatching); the dragon and the textured
  floor with a mirror are held out: their rows for the chosen n are the verdict, the other n's rows
  are shown for what they are.
- Reuse: the README's best configuration per style (BENCHMARKS.md, equal_time), re-measured on every
  scene.

Second protocol, `--protocol pixel` (added after the same-ray results above were seen; the one the
issue's goal is judged on, BENCHMARKS.md says why): against the pixel-integrated reference.
- What a renderer converges to is the pixel's integral over its footprint (box filter) of g(E[L |
  x]). The same-ray protocol compares a spatial filter with g at one sub-pixel point; here every
  render is compared with that integral.
- Reference: the mean R of four independent parts (seeds 1000 .. 1003, not the renders' 0 ..
  SEEDS-1), each PIXEL_REF = (32 camera samples per pixel, direct application with n = 1024),
  recorded once per scene as an expectation buffer and restyled to each style: 128 camera samples
  per pixel in all. Its own floor is measured and reported: the variance of R's error from the
  parts' spread, and the bias that direct application's finite n leaves, bounded by its change from
  n = 256 (check buffers on the camera rays of parts 0 and 1; their product of differences removes
  the children's noise), pixel_reference says how.
- Methods, each with its own split of the budget into camera samples per pixel (spp) and children
  (n): fixed counts over the (spp, n) grid PIXEL_FIXED (the equal-time curve is the lower envelope
  over all of them, the tree sampler's best split at every time); expectation denoising over
  PIXEL_EXPECTATION (spp, n, and where g meets D: k coverage points per pixel, or the camera samples
  with k = 0; u the uncertainty g is averaged over, docs/denoise.md); image denoising over
  PIXEL_IMAGE; reuse (the README's configuration) at spp 1, 4 and 8. Styles cel and hatching (the
  goal's; the colour map is left out to fit the time).
- MSE, bias^2 and variance as above with e_s = render_s - R; R's own error is common to all seeds,
  so it lands in bias^2. Timing interleaved as above. The setting of each denoiser and of reuse is
  chosen on the Cornell box only (the best ratio averaged over cel and hatching); the held-out
  scenes are reported at that choice.
- The chosen expectation setting's floor (`--floor`, method_floor): the same setting with 8x its
  camera samples and 8x n, against R. The ratio it would have at its own time if its MSE were that
  floor bounds what a less noisy D alone could bring; below the goal, the goal needs a change to
  what D is, not more samples or a better OIDN.

    .venv/bin/python benchmarks/denoise.py [--size 128] [--seeds 3]
        [--scenes cornell-box dragon floor-mirror] [--protocol same-ray|pixel|both] [--report]
    # R's bias from its n, estimated (bias_check)
    .venv/bin/python benchmarks/denoise.py --bias-check --scenes cornell-box
    # the chosen setting's floor (method_floor)
    .venv/bin/python benchmarks/denoise.py --floor

Results are cached in benchmarks/.cache/denoise_*.npz/json per scene (delete to recompute);
`--report` only writes the BENCHMARKS.md section and docs/denoise.png from the cache.
"""
from __future__ import annotations

import argparse
import json
import os
import re
import statistics
import time

import numpy as np
from _report import image_grid, machine_description, median_time, write_section
from equal_time import envelope, fixed_mse_at

import styletrace
from styletrace import render as denoised_render
from styletrace.frontends import api
from styletrace.gate import mi
from styletrace.lookdev.record import render_buffer

styletrace.init()

CACHE = os.path.join(os.path.dirname(__file__), ".cache")
REF = 4096
SCENES = ("cornell-box", "dragon", "floor-mirror")
HELD_OUT = ("dragon", "floor-mirror")
STYLES = ("cel", "hatching", "color_map")
GOAL = 10.0  # expectation denoising vs the fixed counts at equal time, cel and hatching
FIXED = (4, 8, 16, 32, 64, 128)
# a first run with n = 1, 2, 4 on the Cornell box found the ratio growing with n (the fixed overhead
# of a render and of the denoiser is amortised); the grid goes on from there
EXPECTATION_N = (4, 8, 16, 32)
IMAGE_N = (4, 16, 64)
POOLED = {"reuse": "pixels", "reuse_mis": "pairwise", "reuse_radius": 3, "reuse_k": 48}
# the README's / BENCHMARKS.md's best reuse configuration per style (chosen on the Cornell box
# there)
REUSE = {"cel": ("reuse m=2:16 K=48 (7x7)", {"inner": "2:16", **POOLED}),
         "hatching": ("reuse m=2:32 K=48 (7x7)", {"inner": "2:32", **POOLED}),
         "color_map": ("reuse m=4 K=48 (7x7)", {"inner": 4, **POOLED})}

# the pixel-integrated protocol (docstring): (spp, n) per reference half, the renders' grids
# per part; R is the mean of one part per seed below (128 camera samples per pixel)
PIXEL_REF = (32, 1024)
# four parts, not two: with two (64 spp) the variance of R's error was 8% of the best hatching MSE
# on the Cornell box
PIXEL_REF_SEEDS = (1000, 1001, 1002, 1003)
PIXEL_CHECK_N = 256
# bias_check's parts (`--bias-check`): 4n, half the camera samples to halve their cost
PIXEL_HIGH = (16, 4096)
PIXEL_STYLES = ("cel", "hatching")
# products spp * n from 2 to 512, small n at many camera samples and large n at few; the envelope
# takes the best
PIXEL_FIXED = (
    (1, 2),
    (1, 4),
    (1, 16),
    (1, 64),
    (2, 8),
    (4, 2),
    (4, 4),
    (4, 16),
    (4, 64),
    (8, 8),
    (16, 2),
    (16, 4),
    (16, 16),
    (32, 16),
    (64, 2),
    (64, 4),
    (128, 4),
)
# a first run with spp up to 8 found expectation and image denoising still improving at spp = 8 (and
# reuse at 4, the most it had): every method's grid goes on from there a third run (the
# interpolation in one Dr.Jit kernel, guides through mirrors) found the denoiser's cost per camera
# sample a third lower and hatching still improving with spp at a fixed number of children per
# pixel: both denoisers' grids went on to 32 and 64 camera samples per pixel the fourth run has
# coverage points (g at k = 64 stratified first hits per pixel, docs/denoise.md step 6): the camera
# samples then only form M, so the grid trades camera samples against children at 32 to 512 children
# per pixel; (spp, n, k, u) with k = 0 the previous method (g at the camera samples), kept at its
# previous choice the fifth adds g averaged over D's uncertainty (u, `--denoise-uncertainty`, step
# 7; its default 0.3 was chosen on the Cornell box at spp 4, n 8, k 64 among 0.15, 0.2, 0.3, 0.45
# and 1): u = 0 rows show it off
PIXEL_EXPECTATION = tuple(
    (spp, n, 64, 0.3)
    for spp, n in (
        (2, 8),
        (2, 16),
        (2, 32),
        (4, 4),
        (4, 8),
        (4, 16),
        (4, 32),
        (8, 8),
        (8, 16),
        (8, 32),
        (16, 4),
        (16, 8),
        (32, 4),
    )
) + ((4, 8, 64, 0.0), (8, 16, 64, 0.0), (32, 4, 0, 0.0))
PIXEL_IMAGE = tuple((spp, n) for spp in (1, 2, 4, 8, 16) for n in (4, 16)) + ((32, 4), (64, 2))
PIXEL_REUSE_SPP = (1, 4, 8)


READING = (
    "Reading. **The 10x goal is not met on any scene** (best: 3.6x, cel on the Cornell box, where "
    "the settings were "
    "chosen; 1.4x to 1.8x on the held-out scenes): a loss. Expectation denoising beats image "
    "denoising on hatching "
    "everywhere (image denoising is *worse* than the fixed counts on hatching, 0.5x to 0.8x: it "
    "smears the "
    "lines, docs/denoise.png) and on cel on the Cornell box and the dragon, but **loses to it on "
    "cel on the "
    "floor-and-mirror scene** (1.66x against 2.01x): a loss. In pictures it is the cleanest of "
    "the four columns "
    "(docs/denoise.png), yet by MSE it is not 10x better, for three measured reasons. (1) The "
    "reference floor: "
    "a reference of n/4 differs from the n = 4096 one by MSE 3e-3 to 6e-3 for cel and hatching; "
    "if a step "
    "style's error falls as 1/sqrt(n), the reference's own error is a third of that, 1e-3 to "
    "2e-3, which is "
    "15-25% of the denoised renders' MSE (7e-3 to 1e-2) and caps any method's ratio at about 10 "
    "to 25 at these "
    "times. (2) Sub-pixel placement: the reference's one camera sample per pixel lands on either "
    "side of a band "
    "boundary that runs through the pixel; D is a smooth field, so boundary pixels disagree with "
    "the reference "
    "seed by seed (this is most of the 'variance' of the denoised rows, whose bias^2 is 1e-3 to "
    "3e-3; the "
    "interpolation of D at each sample's film position removed about a fifth of it, "
    "docs/denoise.md). "
    "(3) Overhead: at 128x128 the denoiser's fixed cost (guides, OIDN, interpolation, the "
    "buffer's transfer: "
    "0.2 to 0.5 s on the loaded machine) buys the fixed sampler 16 to 32 more children per pixel. "
    "Its MSE falls "
    "slowly with n (cel, Cornell box: 1.48e-2 at n = 4, 8.7e-3 at n = 32): what is left is the "
    "denoiser's blur "
    "and the boundary placement, not the children's noise. Reuse (`reuse=pixels` with a "
    "refinement round, the "
    "README's best configuration) beats expectation denoising at equal time on five of the six "
    "(scene, style) "
    "pairs. **Reuse re-measured**: its 4x holds on the Cornell box for hatching (4.95x) but not "
    "for cel in this "
    "run (3.12x; 4.02x in the equal_time section, whose fixed grid and timings differ); on the "
    "held-out scenes it "
    "does not hold (dragon 1.72x cel, 2.58x hatching; floor and mirror 1.93x, 2.07x). Timing "
    "noise: the same "
    "configuration's median time moved by up to 2x between two runs of this script on the shared "
    "machine, so "
    "each ratio carries roughly +-40%; the MSE columns are unaffected (the same seeds give the "
    "same images). "
    "Disclosure: two rules of the method (albedo 1 for specular first hits, D below the "
    "denoiser's resolution set "
    "to 0) were added after seeing the floor-and-mirror images (coloured speckle in the mirror); "
    "they change no "
    "MSE on the Cornell box or the dragon (identical to 4 digits before and after), but that "
    "scene is not "
    "strictly held out for them. The colour map is not part of the goal; there the three filters "
    "reach 1.2x to "
    "3.1x over "
    "the fixed counts, reuse the highest on two of three scenes."
)

PIXEL_READING = (
    "Reading (pixel protocol). This run's change (docs/denoise.md, step 5): D's lookup finds the "
    "neighbours that show "
    "a vertex's own surface by the vertex's own albedo; it compared them with the pixel's mean "
    "albedo, which on a "
    "silhouette matches neither surface, so every neighbour failed and the vertex took its "
    "pixel's mixed D. The rest "
    "is the previous run's method (coverage points, step 6; the style averaged over D's residual "
    "error, step 7), and "
    "the script chose the same setting on the Cornell box: 8 camera samples per pixel, n = 8, 64 "
    "points, u = 0.3. "
    "**The 10x goal is not met**: 9.23x (cel) and 9.76x (hatching) on the Cornell box, where the "
    "setting was "
    "chosen; held out 3.32x and 5.52x (dragon), 4.95x and 6.47x (floor and mirror): losses. At "
    "that setting the MSE "
    "fell on all six pairs (Cornell box 1.94e-3 to 1.83e-3 and 1.44e-3 to 1.33e-3, dragon 3.03e-3 "
    "to 2.65e-3 and "
    "3.72e-3 to 3.56e-3, floor and mirror 1.22e-3 to 1.05e-3 and 1.81e-3 to 1.59e-3); the Cornell "
    "box's hatching "
    "ratio still fell from 10.47x to 9.76x, because the ratio's time axis moves with the "
    "machine's load (about "
    "+-15% on a ratio between runs, measured before). Previous runs: 8.75x/10.47x, 2.90x/5.28x, "
    "4.26x/5.68x, and "
    "before the coverage points 4.53x/4.06x, 2.06x/4.09x, 1.70x/2.21x. It beats image denoising "
    "and reuse on all "
    "six pairs. **What limits it, measured (`--floor`, the last two columns)**: the chosen "
    "setting with 8x its "
    "camera samples and 8x n (64x the children; seeds 0 and 1) still has 64% to 82% of its MSE "
    "against R, and "
    "122% for the Cornell box's hatching: most of the error left is not the noise of M. If the "
    "setting's MSE were "
    "that floor, its ratios at its own time would be 12.8x/8.0x (Cornell box), 5.2x/8.3x (dragon) "
    "and 7.2x/7.9x "
    "(floor and mirror): **no less noisy D (more samples, a better denoiser) brings the held-out "
    "scenes to 10x.** "
    "Pixels with a depth edge inside them (first hits whose distances spread by over 3%: "
    "silhouettes) hold 3% to 25% "
    "of the floor in 2% to 6% of the pixels (before this run's lookup fix, the dragon's cel floor "
    "had 38% of 2.08e-3 "
    "there; /tmp analysis, seed 0). The rest lies on smooth surfaces, where three things remain: "
    "R's own error (its "
    "estimated squared bias on cel is 81% of the setting's MSE on the Cornell box and 283% on the "
    "floor and mirror, "
    "so there a converged method would move away from R; on the Cornell box's hatching the floor "
    "lies above the "
    "setting's MSE), D's one value per pixel (the points of a pixel share it where E[L] varies "
    "inside the pixel: "
    "the dragon's relief at 128x128) and OIDN's blur of E[L] where only the lighting changes. "
    "Reaching 10x needs a D "
    "that resolves E[L] below the pixel and a reference converged on step styles (far more "
    "children near the band "
    "thresholds); neither is in this run. **A caveat on the averaging over D's error, measured in "
    "the previous run**: "
    "R's own bias is a smoothing of the same kind, so part of the averaging's gain on cel is "
    "agreement with R; "
    "against R at 4x its n (`high_reference`) it lowered the Cornell box's cel MSE by 17% rather "
    "than 37%; the "
    "ratios against that reference are in the tenth column. Disclosure: the lookup fix was found "
    "by looking at the "
    "held-out dragon's floor (its silhouette pixels), and checked on the Cornell box, where it "
    "lowered both styles' "
    "MSE (1.94e-3 to 1.83e-3, 1.44e-3 to 1.33e-3) before it was kept; a wider lookup window where "
    "no neighbour "
    "qualifies (5 x 5) lowered the dragon's MSE further but raised the Cornell box's (1.83e-3 to "
    "1.85e-3, 1.33e-3 "
    "to 1.36e-3) and was not kept. Earlier choices (previous runs): k = 64, u = 0.3 and its 3 x 3 "
    "neighbourhood on "
    "the Cornell box alone; a refinement pass and a half-resolution D tried there and dropped. "
    "The colour map is "
    "left out of this protocol (not part of the goal; time)."
)
PROTOCOLS = (
    "**Which protocol the goal is judged on: the pixel-integrated one.** What a renderer "
    "converges to, and what the "
    "picture shows, is each pixel's integral over its footprint (box filter) of g(E[L | x]). The "
    "same-ray protocol "
    "compares every render with g at one sub-pixel point, the reference's own camera ray: it "
    "counts as error a "
    "denoiser's smooth D where D is closer to the pixel's value than that one point is, and it "
    "gives no method the "
    "choice of spending its budget on camera samples rather than children. **The pixel protocol "
    "was added after the "
    "same-ray results had been seen** (their reading named sub-pixel placement as one reason for "
    "the shortfall), so "
    "the choice of protocol was not made blind; both are reported, the same-ray tables as they "
    "were measured (not "
    "re-run; their machine line names their commit), and the verdict is given under both."
)


def floor_mirror(size: int) -> dict:
    """A held-out scene: a checkerboard-textured floor, a mirror, a diffuse sphere, a back wall,
    one area light."""
    T = mi.ScalarTransform4f
    grey = {"type": "diffuse", "reflectance": {"type": "rgb", "value": [0.6, 0.6, 0.6]}}
    return {
        "type": "scene",
        "sensor": {
            "type": "perspective",
            "fov": 45,
            "to_world": T().look_at(origin=[0, 1.3, 4.5], target=[0, 0.7, 0], up=[0, 1, 0]),
            "film": {"type": "hdrfilm", "width": size, "height": size, "rfilter": {"type": "box"}},
            "sampler": {"type": "independent", "sample_count": 1},
        },
        "floor": {
            "type": "rectangle",
            "to_world": T().rotate([1, 0, 0], -90).scale(4),
            "bsdf": {
                "type": "diffuse",
                "reflectance": {
                    "type": "checkerboard",
                    "color0": {"type": "rgb", "value": [0.15, 0.15, 0.2]},
                    "color1": {"type": "rgb", "value": [0.8, 0.75, 0.6]},
                    "to_uv": mi.ScalarTransform4f().scale([8, 8, 1]),
                },
            },
        },
        "wall": {"type": "rectangle", "to_world": T().translate([0, 2, -2]).scale(4), "bsdf": grey},
        "mirror": {
            "type": "rectangle",
            "to_world": T().translate([-1.1, 0.9, -0.8]).rotate([0, 1, 0], 35).scale([0.7, 0.9, 1]),
            "bsdf": {"type": "conductor"},
        },
        "sphere": {
            "type": "sphere",
            "center": [0.7, 0.55, 0.1],
            "radius": 0.55,
            "bsdf": {"type": "diffuse", "reflectance": {"type": "rgb", "value": [0.7, 0.25, 0.2]}},
        },
        "light": {
            "type": "rectangle",
            "to_world": T().translate([0.3, 3.2, 0.5]).rotate([1, 0, 0], 90).scale(0.6),
            "emitter": {"type": "area", "radiance": {"type": "rgb", "value": [14, 13, 12]}},
        },
    }


def load(name: str, size: int) -> mi.Scene:
    return (
        api.load_scene(floor_mirror(size))
        if name == "floor-mirror"
        else api.load_scene(name, size, size)
    )


def methods(style: str) -> list[tuple[str, str, dict]]:
    """(label, kind, keywords): kind "fixed", "expectation", "image" or "reuse"."""
    out = [(f"fixed n={n}", "fixed", {"inner": n}) for n in FIXED]
    out += [
        (
            f"denoise expectation n={n}",
            "expectation",
            {"inner": n, "denoise": "expectation", "coverage": 0},
        )
        for n in EXPECTATION_N
    ]
    out += [(f"denoise image n={n}", "image", {"inner": n, "denoise": "image"}) for n in IMAGE_N]
    label, kw = REUSE[style]
    return out + [(label, "reuse", kw)]


def one(scene, style, kw, seed):
    kw = dict(kw)
    method = kw.pop("denoise", None)
    spp = kw.pop("spp", 1)
    t = time.perf_counter()
    if method is None:
        img = api.render(scene, style=style, spp=spp, seed=seed, **kw)
    else:
        img = denoised_render(scene, style=style, spp=spp, seed=seed, denoise=method, **kw)
    return np.asarray(img, dtype=np.float64)[..., :3], time.perf_counter() - t


def references(name, scene, size, seeds):
    """Per seed, {style: reference image}; plus the REF/4 check (seed 0, cel) as an MSE per
    style."""
    os.makedirs(CACHE, exist_ok=True)
    out = []
    for s in range(seeds):
        path = os.path.join(CACHE, f"denoise_ref_{name}_{size}_{REF}_seed{s}.npz")
        if not os.path.exists(path):
            t = time.perf_counter()
            buf = render_buffer(scene, style="cel", spp=1, inner=REF, seed=s)
            imgs = {st: styletrace.restyle(buf, style=st) for st in STYLES}
            print(
                f"  reference {name} seed {s}: n={REF}, {time.perf_counter() - t:.0f} s", flush=True
            )
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


def measure_methods(name, scene, style, ms, seeds, reference_of, second=None):
    """Every method of `ms` (label, kind, keywords) rendered for seeds 0 .. seeds-1, interleaved,
    and scored against `reference_of(seed)`: (result rows by "style|label", seed 0's image by
    "style|label"). `second`: another reference image, every row's MSE against it kept too
    ("mse_hi", `high_reference`)."""
    for label, _, kw in ms:  # warm-up: kernels compiled, caches filled
        one(scene, style, kw, 999)
    imgs = {label: [] for label, _, _ in ms}
    secs = {label: [] for label, _, _ in ms}
    for s in range(seeds):  # interleaved: every method of this comparison under the same load
        for label, _, kw in ms:
            img, t = one(scene, style, kw, s)
            imgs[label].append(img)
            secs[label].append(t)
    results, keep = {}, {}
    for label, kind, kw in ms:
        err = np.stack(imgs[label]) - np.stack([reference_of(s) for s in range(seeds)])
        var = float(np.mean(np.var(err, axis=0, ddof=1)))
        bias2 = float(np.mean(err.mean(axis=0) ** 2)) - var / seeds
        mse = float(np.mean(err ** 2))
        results[f"{style}|{label}"] = {
            "style": style,
            "method": label,
            "kind": kind,
            "spp": kw.get("spp", 1),
            "secs": statistics.median(secs[label]),
            "mse": mse,
            "bias2": bias2,
            "var": var,
        }
        if second is not None:
            results[f"{style}|{label}"]["mse_hi"] = float(
                np.mean((np.stack(imgs[label]) - second) ** 2)
            )
        keep[f"{style}|{label}"] = imgs[label][0].astype(np.float32)
        print(f"  {name} {style} {label}: {statistics.median(secs[label]):.2f} s, MSE {mse:.3e} "
              f"(bias^2 {bias2:.2e}, var {var:.2e})", flush=True)
    return results, keep


def measure_scene(name, size, seeds):
    scene = load(name, size)
    refs, check = references(name, scene, size, seeds)
    results, keep = {}, {}
    for style in STYLES:
        got, imgs = measure_methods(
            name, scene, style, methods(style), seeds, lambda s: refs[s][style]
        )
        results.update(got)
        keep.update(imgs)
        keep[f"{style}|reference"] = refs[0][style].astype(np.float32)
    with open(os.path.join(CACHE, f"denoise_results_{name}_{size}.json"), "w") as f:
        json.dump({"results": results, "ref_check": check, "seeds": seeds}, f, indent=1)
    np.savez(os.path.join(CACHE, f"denoise_images_{name}_{size}.npz"), **keep)


def pixel_methods(style: str) -> list[tuple[str, str, dict]]:
    """The pixel protocol's (label, kind, keywords), every kind over its (spp, n) grid."""
    out = [(f"fixed spp={spp} n={n}", "fixed", {"spp": spp, "inner": n}) for spp, n in PIXEL_FIXED]
    out += [
        (
            f"denoise expectation spp={spp} n={n} k={k} u={u:g}",
            "expectation",
            {
                "spp": spp,
                "inner": n,
                "denoise": "expectation",
                "coverage": k,
                "denoise_uncertainty": u,
            },
        )
        for spp, n, k, u in PIXEL_EXPECTATION
    ]
    out += [
        (f"denoise image spp={spp} n={n}", "image", {"spp": spp, "inner": n, "denoise": "image"})
        for spp, n in PIXEL_IMAGE
    ]
    label, kw = REUSE[style]
    return out + [(f"{label} spp={spp}", "reuse", {"spp": spp, **kw}) for spp in PIXEL_REUSE_SPP]


def ref_path(name, size, seed, spp, n) -> str:
    """Where `ref_part` caches a part."""
    return os.path.join(CACHE, f"denoise_pixref_{name}_{size}_{spp}x{n}_seed{seed}.npz")


def ref_part(name, scene, size, seed, spp, n, what="pixel reference"):
    """One part of the pixel reference: `spp` camera samples per pixel, direct application at
    `n`, seed `seed`, restyled to every style; rendered once (`what` names it in the log) and
    cached, float64 per style. `scene` None: read from the cache only."""
    path = ref_path(name, size, seed, spp, n)
    if scene is not None and not os.path.exists(path):
        t = time.perf_counter()
        buf = render_buffer(scene, style="cel", spp=spp, inner=n, seed=seed)
        got = {st: styletrace.restyle(buf, style=st) for st in STYLES}
        del buf
        print(
            f"  {what} {name} seed {seed}: spp={spp} n={n}, {time.perf_counter() - t:.0f} s",
            flush=True,
        )
        np.savez(path, **got)
    with np.load(path) as z:
        return {st: z[st].astype(np.float64) for st in STYLES}


def pixel_reference(name, scene, size):
    """R = the mean of the PIXEL_REF parts per style, and its floor per style: "var", the
    variance of R's error (the parts' variance over K, ddof 1, averaged over pixels: camera
    samples and children together), and "n2", the squared bias that direct application's finite n
    adds, bounded from its change between PIXEL_CHECK_N and n: with C_k the check buffer on part
    k's camera rays, mean((C_0 - A_0) (C_1 - A_1)) estimates the squared change without the
    children's noise (the two pairs are independent), and the bias at n is below that change (it
    shrinks as n grows); "n_raw" is MSE(C_0 - A_0), noise included, the figure the same-ray
    protocol printed."""
    os.makedirs(CACHE, exist_ok=True)
    spp, n = PIXEL_REF
    parts = [ref_part(name, scene, size, seed, spp, n) for seed in PIXEL_REF_SEEDS]
    checks = [ref_part(name, scene, size, seed, spp, PIXEL_CHECK_N) for seed in PIXEL_REF_SEEDS[:2]]
    k = len(parts)
    ref = {st: np.mean([p[st] for p in parts], axis=0) for st in STYLES}
    floor = {}
    for st in STYLES:
        d0, d1 = (checks[i][st] - parts[i][st] for i in range(2))
        floor[st] = {"var": float(np.mean(np.var([p[st] for p in parts], axis=0, ddof=1))) / k,
                     "n2": float(np.mean(d0 * d1)), "n_raw": float(np.mean(d0 ** 2))}
    return ref, floor


def bias_check(name, size) -> dict:
    """R's bias from direct application at n = PIXEL_REF[1], estimated rather than bounded
    (pixel_reference bounds it): with the squared bias changes d1 (PIXEL_CHECK_N to n) and d2 (n
    to PIXEL_HIGH[1] = 4n), each from two independent pairs as in pixel_reference, a bias falling
    as n^-a gives d1 / d2 = (4^a)^2, and the squared bias left at n is d2 / (1 - 4^-a)^2.
    PIXEL_HIGH has fewer camera samples: the pairs' expected difference does not depend on them,
    only their noise does. Cached in denoise_pixel_bias_<scene>_<size>.json; minutes per part."""
    scene = load(name, size)
    spp, n = PIXEL_REF
    hs, hn = PIXEL_HIGH

    def part(seed, rs, rn):
        return ref_part(name, scene, size, seed, rs, rn, "bias check")
    seeds = PIXEL_REF_SEEDS[:2]
    low = [part(s_, spp, PIXEL_CHECK_N) for s_ in seeds]
    mid = [part(s_, spp, n) for s_ in seeds]
    high = [part(s_, hs, hn) for s_ in seeds]
    out = {}
    for st in STYLES:
        d1 = float(np.mean((low[0][st] - mid[0][st]) * (low[1][st] - mid[1][st])))
        d2 = float(np.mean((mid[0][st] - high[0][st]) * (mid[1][st] - high[1][st])))
        four_a = np.sqrt(d1 / d2) if d1 > 0 and d2 > 0 else float("nan")
        left = d2 / (1 - 1 / four_a) ** 2 if four_a > 1 else float("nan")
        out[st] = {"d1": d1, "d2": d2, "four_a": float(four_a), "bias2_at_n": float(left)}
        print(
            f"  bias check {name} {st}: d1 {d1:.2e}, d2 {d2:.2e}, 4^a {four_a:.2f}, squared bias "
            f"at n={n} "
            f"{left:.2e}",
            flush=True,
        )
    with open(os.path.join(CACHE, f"denoise_pixel_bias_{name}_{size}.json"), "w") as f:
        json.dump(out, f, indent=1)
    return out


def measure_scene_pixel(name, size, seeds):
    scene = load(name, size)
    ref, floor = pixel_reference(name, scene, size)
    for st in PIXEL_STYLES:  # the floor every MSE of this scene includes, before anything is timed
        print(
            f"  R's floor {name} {st}: variance {floor[st]['var']:.2e}, n's squared bias change "
            f"{floor[st]['n2']:.2e} "
            f"(with noise {floor[st]['n_raw']:.2e})",
            flush=True,
        )
    results, keep = {}, {}
    high = high_reference(name, size)
    for style in PIXEL_STYLES:
        got, imgs = measure_methods(
            name,
            scene,
            style,
            pixel_methods(style),
            seeds,
            lambda s: ref[style],
            None if high is None else high[style],
        )
        results.update(got)
        keep.update(imgs)
        keep[f"{style}|reference"] = ref[style].astype(np.float32)
    with open(os.path.join(CACHE, f"denoise_pixel_results_{name}_{size}.json"), "w") as f:
        json.dump(
            {
                "results": results,
                "ref_floor": floor,
                "seeds": seeds,
                "load_at_end": os.getloadavg(),
            },
            f,
            indent=1,
        )
    np.savez(os.path.join(CACHE, f"denoise_pixel_images_{name}_{size}.npz"), **keep)


def ratios(results: dict, style: str, key: str = "mse") -> dict[str, tuple[float, str]]:
    """Each method's fixed-counts MSE at its time over its MSE (`key`: "mse", or "mse_hi" against
    the second reference, the fixed counts' envelope then taken over their MSE against it too)."""
    rows = [r for r in results.values() if r["style"] == style]
    curve = envelope([(r["secs"], r[key]) for r in rows if r["kind"] == "fixed"])
    out = {}
    for r in rows:
        if r["kind"] != "fixed":
            at, mark = fixed_mse_at(curve, r["secs"])
            out[r["method"]] = (at / r[key], mark)
    return out


def high_reference(name, size):
    """The second reference, where `--bias-check` has rendered its parts: the mean of its
    PIXEL_HIGH parts (16 camera samples per pixel, n = 4096, seeds 1000 and 1001), per style;
    None where they are not cached. Its direct application's bias is that of 4x R's n
    (bias_check: 1.3x to 3.5x smaller than R's), its camera-sample variance 4x R's (32 camera
    samples per pixel, not 128): a measured check of what R's bias does to the ratios, where
    corrected_mse is an extrapolation."""
    hs, hn = PIXEL_HIGH
    if not all(os.path.exists(ref_path(name, size, s, hs, hn)) for s in PIXEL_REF_SEEDS[:2]):
        return None
    parts = [ref_part(name, None, size, s, hs, hn) for s in PIXEL_REF_SEEDS[:2]]
    return {st: np.mean([p[st] for p in parts], axis=0) for st in PIXEL_STYLES}


#: the method's own floor (`method_floor`): its chosen setting with FLOOR_SCALE x the camera samples
#: and x n
FLOOR_SCALE = 8
FLOOR_SEEDS = (0, 1)


def floor_path(name, size) -> str:
    return os.path.join(CACHE, f"denoise_pixel_floor_{name}_{size}.json")


def method_floor(name, size, label: str) -> dict:
    """Where expectation denoising's setting `label` goes as its samples grow: the same k and u
    with FLOOR_SCALE x the camera samples and FLOOR_SCALE x n (64x the children), MSE against R
    per style, mean over FLOOR_SEEDS. What remains there is no noise of M to speak of: the bias
    of D (OIDN's, the interpolation's at the points), the points' own error and R's error.
    Compared with the fixed counts' MSE at the setting's own time it bounds what any lower-noise
    D could gain at that time (`pixel_body`)."""
    spp, n, k, u = (
        float(v) for v in re.search(r"spp=(\d+) n=(\d+) k=(\d+) u=([\d.]+)", label).groups()
    )
    scene = load(name, size)
    imgs = np.load(os.path.join(CACHE, f"denoise_pixel_images_{name}_{size}.npz"))
    out = {"setting": label, "scale": FLOOR_SCALE, "seeds": list(FLOOR_SEEDS)}
    edges = depth_edges(scene, size)
    out["edge_pixels"] = float(edges.mean())
    for st in PIXEL_STYLES:
        ref = imgs[f"{st}|reference"].astype(np.float64)
        errs = []
        for seed in FLOOR_SEEDS:
            img = denoised_render(
                scene,
                style=st,
                spp=int(spp) * FLOOR_SCALE,
                inner=int(n) * FLOOR_SCALE,
                seed=seed,
                denoise="expectation",
                coverage=int(k),
                denoise_uncertainty=u,
            )
            errs.append(np.mean((np.asarray(img, dtype=np.float64)[..., :3] - ref) ** 2, axis=-1))
        err = np.mean(errs, axis=0)
        out[st] = float(err.mean())
        out[f"{st}_edge_share"] = float(err[edges].sum() / err.sum())
        print(
            f"  floor {name} {st}: {out[st]:.3e} ({label}, x{FLOOR_SCALE} spp and n); "
            f"{100 * out[f'{st}_edge_share']:.0f}% of it in the {100 * edges.mean():.0f}% of "
            f"pixels with a depth edge",
            flush=True,
        )
    with open(floor_path(name, size), "w") as f:
        json.dump(out, f, indent=1)
    return out


#: a pixel has a depth edge where its camera samples' distances from the camera spread by more than
#: this fraction (silhouettes, creases, relief), or where some of them miss the scene
EDGE_SPREAD = 0.03


def depth_edges(scene, size) -> np.ndarray:
    """Pixels (H x W bool) whose first hits lie at different depths (EDGE_SPREAD), from 16 camera
    rays per pixel: where one D per pixel stands for several surfaces or for a surface whose E[L]
    varies inside the pixel."""
    buf = render_buffer(scene, style="identity", spp=16, inner=1, seed=12345)
    a = buf.arrays
    cam = np.asarray(scene.sensors()[0].world_transform().translation(), dtype=np.float64).ravel()[
        :3
    ]
    dist = np.linalg.norm(a["p"].T.astype(np.float64) - cam, axis=1)
    hit = a["slot"] >= 0
    pixels = size * size
    lo, hi = np.full(pixels, np.inf), np.full(pixels, -np.inf)
    np.minimum.at(lo, a["pixel"][hit], dist[hit])
    np.maximum.at(hi, a["pixel"][hit], dist[hit])
    hits = np.bincount(a["pixel"][hit], minlength=pixels)
    some = hits > 0
    spread = np.where(some, (hi - lo) / np.where(some, lo, 1.0), 0.0)
    return (
        (spread > EDGE_SPREAD) | (some & (hits < np.bincount(a["pixel"], minlength=pixels)))
    ).reshape(size, size)


def setting(label: str) -> str:
    """A method's settings without the style's own part (reuse's m differs per style, REUSE)."""
    return (
        "reuse " + label.rsplit(" ", 1)[1]
        if label.startswith("reuse") and "spp=" in label
        else label
    )


def best_of(cornell: dict, kind: str) -> dict[str, str]:
    """The settings of `kind` with the best mean ratio over cel and hatching on the Cornell box
    (they are chosen there only), as {style: that setting's label}."""
    by = {}
    for r in cornell.values():
        if r["kind"] == kind and r["style"] in ("cel", "hatching"):
            by.setdefault(setting(r["method"]), {})[r["style"]] = r["method"]
    score = {
        k: np.mean([ratios(cornell, st)[lb][0] for st, lb in v.items()]) for k, v in by.items()
    }
    return by[max(score, key=score.get)]


def load_cached(prefix: str, size: int) -> dict:
    data = {}
    for name in SCENES:
        path = os.path.join(CACHE, f"{prefix}_{name}_{size}.json")
        if os.path.exists(path):
            with open(path) as f:
                data[name] = json.load(f)
    return data


def same_ray_body(data: dict, size: int) -> tuple[str, list]:
    """The same-ray protocol's subsection (headings one level below the section's) and its figure
    panels."""
    cornell = data["cornell-box"]["results"]
    pick_e = best_of(cornell, "expectation")["cel"]
    pick_i = best_of(cornell, "image")["cel"]
    sections, verdicts, panels = [], [], []
    for name, d in data.items():
        res = d["results"]
        held = " (held out)" if name in HELD_OUT else " (settings chosen here)"
        lines = [
            f"#### {name}{held}",
            "",
            f"Reference: direct application, n={REF}, seed by seed. A reference of n={REF // 4} "
            f"differs from it "
            f"(seed 0) by MSE "
            + ", ".join(f"{st} {v:.2e}" for st, v in d["ref_check"].items())
            + ": the order of the floor every MSE below includes.",
            "",
            "| style | method | s (median) | MSE | bias^2 | variance | fixed-n MSE at this time / "
            "MSE |",
            "|---|---|---:|---:|---:|---:|---:|",
        ]
        for style in STYLES:
            rat = ratios(res, style)
            for r in res.values():
                if r["style"] != style:
                    continue
                g = (
                    ""
                    if r["kind"] == "fixed"
                    else f"{rat[r['method']][1]}{rat[r['method']][0]:.2f}"
                )
                label = f"**{r['method']}**" if r["method"] in (pick_e, pick_i) else r["method"]
                lines.append(
                    f"| {style} | {label} | {r['secs']:.2f} | {r['mse']:.3e} | {r['bias2']:.2e} | "
                    f"{r['var']:.2e} | {g} |"
                )
            if style in ("cel", "hatching"):
                e, i = rat[pick_e][0], rat[pick_i][0]
                reuse = rat[REUSE[style][0]][0]
                verdicts.append(
                    f"| {name} | {style} | {e:.2f}x | "
                    f"{'met' if e >= GOAL else '**LOSS: not met**'} | "
                    f"{i:.2f}x | {'yes' if e > i else '**no: LOSS**'} | {reuse:.2f}x |"
                )
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
    body = "\n".join(
        [
            "### Same-ray protocol (the first measurement)",
            "",
            f"{size}x{size}, 1 camera sample per pixel, seeds "
            f"0..{next(iter(data.values()))['seeds'] - 1}, each render "
            "against a reference of the same seed (the same camera rays). Protocol: the script's "
            "docstring. Every "
            "method of one (scene, style) was timed interleaved in one loop. Settings of the "
            f"denoisers chosen on the Cornell box alone (expectation: `{pick_e}`, image: "
            f"`{pick_i}`, in bold); the "
            "dragon and the floor-and-mirror scene are held out. Last column: the fixed counts' "
            "MSE at the method's "
            "time over the method's MSE (above 1: better than the tree sampler at equal time; ≥: "
            "the method is "
            "faster than every fixed count, so compared with the cheapest; ≤: slower than every "
            "fixed count).",
            "",
            "| scene | style | expectation ratio | goal | image-denoising ratio | expectation "
            "beats image | reuse ratio |",
            "|---|---|---:|---|---:|---|---:|",
            *verdicts,
            "",
            READING,
            "",
            *sections,
            "",
        ]
    )
    return body, panels


SAME_RAY_START, SAME_RAY_END = "<!-- same-ray -->", "<!-- /same-ray -->"


def kept_same_ray() -> str | None:
    """The same-ray subsection as BENCHMARKS.md holds it, for a report written without its cache
    (the measurement stays on record; it is not re-run by a pixel-protocol run). A section
    written before the pixel protocol existed is the same-ray one as a whole: its headings are
    moved one level down."""
    from _report import REPORT
    if not REPORT.exists():
        return None
    text = REPORT.read_text()
    m = re.search(r"<!-- section:denoise -->\n(.*?)\n<!-- /section:denoise -->", text, re.S)
    if m is None:
        return None
    sec = m.group(1)
    if SAME_RAY_START in sec:
        return sec.split(SAME_RAY_START, 1)[1].split(SAME_RAY_END, 1)[0].strip("\n")
    lines = []
    # the machine line (and its commit) stays: it says where this was measured
    for line in sec.splitlines():
        if line.startswith("## "):
            line = "### Same-ray protocol (the first measurement)"
        elif line.startswith("### "):
            line = "#" + line
        lines.append(line)
    return "\n".join(lines).strip("\n")


def n_bias(name: str, size: int, style: str, fl: dict) -> tuple[float, str]:
    """R's squared bias from its n: bias_check's estimate where it was run, else the change from
    PIXEL_CHECK_N (a bound only if the bias falls at least as 1/sqrt(n), which bias_check found
    false for cel)."""
    path = os.path.join(CACHE, f"denoise_pixel_bias_{name}_{size}.json")
    if os.path.exists(path):
        with open(path) as f:
            b = json.load(f)[style]
        if np.isfinite(b["bias2_at_n"]):
            return b["bias2_at_n"], "estimated"
    return max(fl[style]["n2"], 0.0), "change from n=256"


def corrected_mse(name: str, size: int, res: dict, style: str) -> dict[str, float] | None:
    """Each method's MSE against the truth T rather than R, estimated where bias_check ran: with
    b = R - T (R's bias from its n), MSE_T = MSE_R + 2 <e, b> + |b|^2, e = render - R. <e, b> is
    estimated from seed 0's image with e_k = render - (R without part k) dotted with part k's
    difference to its n = 4n part (independent of e_k's noise; its mean is b (1 - 4^-a)),
    averaged over the two parts; |b|^2 is bias_check's. An estimate resting on bias_check's power
    law, one seed, and R's variance left in; None where it cannot be formed."""
    path = os.path.join(CACHE, f"denoise_pixel_bias_{name}_{size}.json")
    if not os.path.exists(path):
        return None
    with open(path) as f:
        b = json.load(f)[style]
    if not (np.isfinite(b["four_a"]) and b["four_a"] > 1):
        return None

    parts = [ref_part(name, None, size, sd, *PIXEL_REF)[style] for sd in PIXEL_REF_SEEDS]
    highs = [ref_part(name, None, size, sd, *PIXEL_HIGH)[style] for sd in PIXEL_REF_SEEDS[:2]]
    scale = 1 / (1 - 1 / b["four_a"])
    with np.load(os.path.join(CACHE, f"denoise_pixel_images_{name}_{size}.npz")) as z:
        out = {}
        for r in res.values():
            if r["style"] != style:
                continue
            img = z[f"{style}|{r['method']}"].astype(np.float64)
            cross = (
                np.mean(
                    [
                        np.mean(
                            (img - np.mean(parts[:k] + parts[k + 1 :], axis=0))
                            * (parts[k] - highs[k])
                        )
                        for k in range(2)
                    ]
                )
                * scale
            )
            out[r["method"]] = r["mse"] + 2 * cross + b["bias2_at_n"]
    return out


def corrected_ratio(name: str, size: int, res: dict, style: str, label: str) -> float | None:
    """The ratio of `label` to the fixed counts' envelope, both with corrected_mse."""
    mse = corrected_mse(name, size, res, style)
    if mse is None:
        return None
    rows = [r for r in res.values() if r["style"] == style]
    curve = envelope([(r["secs"], mse[r["method"]]) for r in rows if r["kind"] == "fixed"])
    return fixed_mse_at(curve, res[f"{style}|{label}"]["secs"])[0] / mse[label]


def bias_sentence(name: str, size: int) -> str:
    """bias_check's estimate for the scene, where it was run (`--bias-check`)."""
    path = os.path.join(CACHE, f"denoise_pixel_bias_{name}_{size}.json")
    if not os.path.exists(path):
        return ""
    with open(path) as f:
        b = json.load(f)
    return (
        f" Estimated (`--bias-check`, two more parts of {PIXEL_HIGH[0]} camera samples at "
        f"n={PIXEL_HIGH[1]}): "
        "squared bias change from 1024 to 4096 "
        + ", ".join(f"{st} {b[st]['d2']:.1e}" for st in PIXEL_STYLES)
        + "; fitted 4^a (the bias's fall per 4x of n) "
        + ", ".join(f"{st} {b[st]['four_a']:.2f}" for st in PIXEL_STYLES)
        + "; squared bias left in R "
        + ", ".join(f"{st} {b[st]['bias2_at_n']:.1e}" for st in PIXEL_STYLES)
        + "."
    )


def fixed_near(res: dict, style: str, t: float) -> str:
    """The fixed (spp, n) on the lower envelope nearest in time to t: the tree sampler's best
    split there."""
    rows = [r for r in res.values() if r["style"] == style and r["kind"] == "fixed"]
    curve = envelope([(r["secs"], r["mse"]) for r in rows])
    on = [r for r in rows if (r["secs"], r["mse"]) in curve]
    return min(on, key=lambda r: abs(np.log(r["secs"] / t)))["method"]


def pixel_body(data: dict, size: int) -> tuple[str, list, list]:
    """The pixel protocol's subsection, its figure panels and its verdict rows."""
    cornell = data["cornell-box"]["results"]
    picks = {kind: best_of(cornell, kind) for kind in ("expectation", "image", "reuse")}
    sections, verdicts, panels = [], [], []
    for name, d in data.items():
        res = d["results"]
        held = " (held out)" if name in HELD_OUT else " (settings chosen here)"
        best = {st: min(r["mse"] for r in res.values() if r["style"] == st) for st in PIXEL_STYLES}
        fl = d["ref_floor"]
        lines = [
            f"#### {name}{held}",
            "",
            f"Reference R: the mean of {len(PIXEL_REF_SEEDS)} independent parts of {PIXEL_REF[0]} "
            f"camera samples "
            f"per pixel, each with direct application at n={PIXEL_REF[1]} (seeds "
            f"{', '.join(map(str, PIXEL_REF_SEEDS))}). Its floor, the variance of R's error: "
            + ", ".join(
                f"{st} {fl[st]['var']:.1e} ({100 * fl[st]['var'] / best[st]:.1f}% of the best "
                f"method's MSE, {best[st]:.2e})"
                for st in PIXEL_STYLES
            )
            + f". Direct application's bias at n={PIXEL_REF[1]}: its squared change from "
            f"n={PIXEL_CHECK_N} is "
            + ", ".join(f"{st} {fl[st]['n2']:.1e}" for st in PIXEL_STYLES)
            + " (noise-free cross estimate, can dip below 0; with the children's noise: "
            + ", ".join(f"{st} {fl[st]['n_raw']:.1e}" for st in PIXEL_STYLES)
            + "); the squared bias left at n=1024 is below that only if the bias falls at least "
            "as 1/sqrt(n)." + bias_sentence(name, size),
            "",
            "| style | method | s (median) | MSE | bias^2 | variance | fixed MSE at this time / "
            "MSE |",
            "|---|---|---:|---:|---:|---:|---:|",
        ]
        for style in PIXEL_STYLES:
            pick = {kind: v[style] for kind, v in picks.items()}
            rat = ratios(res, style)
            rows = [r for r in res.values() if r["style"] == style]
            curve = envelope([(r["secs"], r["mse"]) for r in rows if r["kind"] == "fixed"])
            for r in rows:
                if r["kind"] == "fixed":
                    g = "envelope" if (r["secs"], r["mse"]) in curve else ""
                else:
                    g = f"{rat[r['method']][1]}{rat[r['method']][0]:.2f}"
                label = f"**{r['method']}**" if r["method"] in pick.values() else r["method"]
                lines.append(
                    f"| {style} | {label} | {r['secs']:.2f} | {r['mse']:.3e} | {r['bias2']:.2e} | "
                    f"{r['var']:.2e} | {g} |"
                )
            e, i, u = (rat[pick[k]][0] for k in ("expectation", "image", "reuse"))
            em = res[f"{style}|{pick['expectation']}"]["mse"]
            # R's floor: its variance and the squared bias of its n; then the ratios against the
            # truth where bias_check ran (corrected_mse; taking the floor off both MSEs would assume
            # R's error independent of the methods', which it is not: they apply g directly too)
            nb, how = n_bias(name, size, style, fl)
            cr = {
                k: corrected_ratio(name, size, res, style, pick[k])
                for k in ("expectation", "image")
            }
            cor = (
                ""
                if cr["expectation"] is None
                else f"{cr['expectation']:.2f}x / {cr['image']:.2f}x"
            )
            hi = ""
            if all("mse_hi" in r for r in rows):
                rh = ratios(res, style, "mse_hi")
                hi = f"{rh[pick['expectation']][0]:.2f}x / {rh[pick['image']][0]:.2f}x"
            mf, bound = "", ""
            if os.path.exists(floor_path(name, size)):
                with open(floor_path(name, size)) as f:
                    fj = json.load(f)
                if fj["setting"] == pick["expectation"]:
                    mf = (
                        f"{fj[style]:.2e} ({100 * fj[style] / em:.0f}%; "
                        f"{100 * fj[f'{style}_edge_share']:.0f}% of it "
                        f"in the {100 * fj['edge_pixels']:.0f}% of pixels with a depth edge)"
                    )
                    bound = f"{e * em / fj[style]:.1f}x"
            verdicts.append(
                f"| {name} | {style} | {e:.2f}x | {'met' if e >= GOAL else '**LOSS: not met**'} | "
                f"{i:.2f}x | {'yes' if e > i else '**no: LOSS**'} | {u:.2f}x | "
                f"{100 * fl[style]['var'] / em:.1f}% + {100 * nb / em:.1f}% ({how}) | {cor} | "
                f"{hi} | "
                f"{mf} | {bound} |"
            )
        sections.append("\n".join(lines))
        imgs = np.load(os.path.join(CACHE, f"denoise_pixel_images_{name}_{size}.npz"))
        for style in PIXEL_STYLES:
            pe, pi = picks["expectation"][style], picks["image"][style]
            t = res[f"{style}|{pe}"]["secs"]
            near = fixed_near(res, style, t)
            panels.append((f"{name}, {style}", [
                (f"{name}, {style}: reference (pixel-integrated)", imgs[f"{style}|reference"]),
                (f"{near}, {res[f'{style}|{near}']['secs']:.2f} s", imgs[f"{style}|{near}"]),
                (f"{pi}, {res[f'{style}|{pi}']['secs']:.2f} s", imgs[f"{style}|{pi}"]),
                (f"{pe}, {t:.2f} s", imgs[f"{style}|{pe}"])]))
    body = "\n".join(
        [
            "### Pixel-integrated protocol (the goal is judged on this one)",
            "",
            f"{size}x{size}, seeds 0..{next(iter(data.values()))['seeds'] - 1}, styles cel and "
            f"hatching, every render "
            "against the brute-force pixel-integrated reference (the box-filtered integral over "
            "the pixel of g(E[L | x]), "
            "independent of the renders' seeds). Each method chooses its camera samples per pixel "
            "(spp) and children (n); "
            "the fixed counts' curve is the lower envelope over their whole (spp, n) grid "
            "('envelope' marks its points). "
            f"Chosen on the Cornell box alone (best ratio averaged over cel and hatching, in "
            f"bold): expectation "
            f"`{picks['expectation']['cel']}`, image `{picks['image']['cel']}`, reuse "
            f"`{setting(picks['reuse']['cel'])}` (m as REUSE per style). Protocol: the script's "
            "docstring (`python benchmarks/denoise.py --protocol pixel`).",
            "",
            "| scene | style | expectation ratio | goal | image-denoising ratio | expectation "
            "beats image | reuse ratio | "
            "R's floor / expectation's MSE (variance + bias^2 of R's n) | expectation / image "
            "ratio against the truth, "
            "R's bias corrected (estimate, corrected_mse) | expectation / image ratio against R "
            "at 4x its n "
            "(measured, high_reference) | the setting's floor: its MSE at 8x its camera samples "
            "and 8x n (and as % of "
            "its MSE; method_floor) | the ratio at the setting's time if its MSE were that floor |",
            "|---|---|---:|---|---:|---|---:|---:|---:|---:|---:|---:|",
            *verdicts,
            "",
            PIXEL_READING,
            "",
            *sections,
        ]
    )
    return body, panels, verdicts


TIMING_HEAD = "#### Cost at 512x512"


def timing_section() -> list[str]:
    """The denoiser's steps timed at 512x512 (`--timing`), where cached."""
    tpath = os.path.join(CACHE, "denoise_timing_512.json")
    if not os.path.exists(tpath):
        return []
    with open(tpath) as f:
        tm = json.load(f)
    return (
        [
            "### Cost at 512x512",
            "",
            "Cornell box, 512x512, 1 camera sample per pixel, n = 8, cel; median of 3 runs, same "
            "shared 2-core "
            "machine (`python benchmarks/denoise.py --timing`; the current method: guides through "
            "mirrors "
            "and glass, each sample's own albedo and emission found by one ray, the interpolation "
            "in one Dr.Jit "
            "kernel, coverage points with D looked up in their kernel).",
            "",
            "| step | s |",
            "|---|---:|",
        ]
        + [f"| {k} | {v:.2f} |" for k, v in tm.items() if k != "size"]
        + [""]
    )


def without_timing(kept: str) -> str:
    """A kept same-ray block without its old timing table (the timing is its own section now),
    keeping the block's last line, the machine line of the run that measured it."""
    if TIMING_HEAD not in kept:
        return kept
    head, rest = kept.split(TIMING_HEAD, 1)
    return head.rstrip("\n") + "\n\n" + rest.strip("\n").splitlines()[-1]


def report(size):
    same = load_cached("denoise_results", size)
    pixel = load_cached("denoise_pixel_results", size)
    if "cornell-box" not in same and "cornell-box" not in pixel:
        raise SystemExit("no Cornell box results cached: run the measurement first")
    if "cornell-box" in same:
        same_body, same_panels = same_ray_body(same, size)
    else:
        kept = kept_same_ray()
        same_body, same_panels = (without_timing(kept) if kept and timing_section() else kept), []
    parts = [
        "## Denoising at a budget: the expectation before g, the image after it "
        "(`benchmarks/denoise.py`)",
        "",
        f"Goal (issue 21): expectation denoising ≥ {GOAL:g}x lower MSE than the fixed-count tree "
        f"sampler at equal "
        "time, cel and hatching, on every scene (Cornell box, dragon, floor and mirror at "
        "128x128; settings "
        "chosen on the Cornell box only), and better than image denoising. Two protocols were "
        "measured; the "
        "paragraph below says which one the goal is judged on and why.",
        "",
        PROTOCOLS,
        "",
    ]
    panels = same_panels
    if "cornell-box" in pixel:
        body, panels, _ = pixel_body(pixel, size)
        parts += [body, ""]
    parts += timing_section()
    if same_body:
        parts += [SAME_RAY_START, same_body, SAME_RAY_END, ""]
    parts.append(machine_description())
    write_section("denoise", "\n".join(parts))
    if panels:
        image_grid(
            panels,
            os.path.join(os.path.dirname(__file__), "..", "docs", "denoise.png"),
            row_height=2.75,
            fontsize=7,
            width=10,
        )


def timing(size: int = 512, runs: int = 3) -> dict:
    """Seconds of the denoising steps at size x size on the Cornell box (1 spp, n = 8), median of
    `runs`: OIDN alone at each quality, the guides' render, the interpolation at the samples, and
    the whole `attach` (guides + OIDN high + interpolation), against the render of the noisy
    buffer itself."""
    from styletrace.denoise import expectation as X
    from styletrace.denoise import oidn
    from styletrace.kernel import guides
    from styletrace.pipeline.passes import Shot
    scene = load("cornell-box", size)
    integ = api.make_integrator(style="cel", inner=8)

    def med(fn):
        return median_time(fn, runs)

    buf = None

    def record():
        nonlocal buf
        buf = render_buffer(scene, spp=1, seed=0, integrator=integ)
    out = {"size": size, "record (render, n=8, 1 spp)": med(record)}
    own = X.own_surface(scene, buf.arrays)
    m = X.expectation(buf, own[1])
    g = guides.first_hit(scene, 1, api.pass_seed(0, 0))
    out["guides (guide pass)"] = med(lambda: guides.first_hit(scene, 1, api.pass_seed(0, 0)))
    for q in ("high", "balanced", "fast"):
        out[f"OIDN {q}"] = med(lambda: oidn.denoise_oidn(m, g.albedo, g.normal, q))
    d = oidn.denoise_oidn(m, g.albedo, g.normal)
    out["own albedo and emission (one ray per sample)"] = med(
        lambda: X.own_surface(scene, buf.arrays)
    )
    out["interpolation at the samples"] = med(lambda: X.at_samples(buf, d, scene, g, own))
    out["attach (guides + OIDN high + interpolation at the camera samples, coverage 0)"] = med(
        lambda: X.attach(buf, Shot(scene, integ, 1, 0)))
    from styletrace.denoise import coverage
    k = coverage.resolve_k("auto", size, size)
    field = X.Field(d, g, float(np.linalg.norm(np.asarray(scene.bbox().extents()))))
    out[
        f"coverage points ({k} per pixel, the 'auto' count at this size; D looked up in the kernel)"
    ] = med(lambda: coverage.points(scene, integ, field, k, 0))
    out[f"attach with coverage points (guides + OIDN high + {k} points per pixel)"] = med(
        lambda: X.attach(buf, Shot(scene, integ, 1, 0), "high", k))
    out["the whole denoised render (render_buffer + attach with coverage 'auto')"] = med(
        lambda: denoised_render(scene, style="cel", spp=1, inner=8, seed=0, denoise="expectation"))
    out["restyle of the denoised buffer"] = med(lambda: styletrace.restyle(buf, style="hatching"))
    with open(os.path.join(CACHE, f"denoise_timing_{size}.json"), "w") as f:
        json.dump(out, f, indent=1)
    return out


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--size", type=int, default=128)
    ap.add_argument("--seeds", type=int, default=3)
    ap.add_argument("--scenes", nargs="*", default=list(SCENES))
    ap.add_argument(
        "--report", action="store_true", help="only write the section and figure from the cache"
    )
    ap.add_argument(
        "--ref", type=int, default=REF, help="the reference's children per camera sample"
    )
    ap.add_argument(
        "--timing", action="store_true", help="only time the denoising steps at 512x512"
    )
    ap.add_argument(
        "--bias-check",
        action="store_true",
        help="estimate the pixel reference's bias from its n on the given scenes (bias_check), "
        "then report",
    )
    ap.add_argument(
        "--floor",
        action="store_true",
        help="measure the chosen expectation setting's floor (method_floor) on the given scenes, "
        "then report",
    )
    ap.add_argument("--protocol", choices=("same-ray", "pixel", "both"), default="both",
                    help="which protocol to measure (the report writes every one that is cached)")
    args = ap.parse_args()
    globals()["REF"] = args.ref
    if args.bias_check:
        for name in args.scenes:
            bias_check(name, args.size)
        args.report = True
    if args.floor:
        cornell = load_cached("denoise_pixel_results", args.size)["cornell-box"]["results"]
        label = best_of(cornell, "expectation")["cel"]
        for name in args.scenes:
            method_floor(name, args.size, label)
        args.report = True
    if args.timing:
        os.makedirs(CACHE, exist_ok=True)
        print(json.dumps(timing(), indent=1))
        return
    if not args.report:
        for name in args.scenes:
            print(f"{name}:", flush=True)
            if args.protocol in ("same-ray", "both"):
                measure_scene(name, args.size, args.seeds)
            if args.protocol in ("pixel", "both"):
                measure_scene_pixel(name, args.size, args.seeds)
    report(args.size)


if __name__ == "__main__":
    main()
