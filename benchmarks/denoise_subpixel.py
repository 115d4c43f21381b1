"""Experiment: the denoised expectation D below the pixel (issue 21's floor).

`benchmarks/denoise.py --floor` found that expectation denoising keeps most of its error against the
reference R when its children grow 64-fold: the error is not the noise of M. One candidate is D's
resolution: one value per pixel, while E[L] varies inside pixels. This script forms M at S x the
film's resolution from the same camera samples (each binned by its own film position,
`expectation.raster`; an empty sub-pixel takes its pixel's M), takes the guides from a guide pass at
S x the resolution, denoises with OIDN `high`, and evaluates the style at the same 64 coverage
points (`coverage.points(scale=S)`, u = 0.3 with the spread per film pixel), against the usual D
from the same buffer. MSE against the pixel protocol's cached R (run `benchmarks/denoise.py
--protocol pixel` first), mean over seeds 0 and 1, at the chosen budget (8 spp, n = 8) and at 64x
the children (64, 64). Not timed: OIDN on S^2 x the pixels costs about S^2 x as much
(BENCHMARKS.md's 512x512 timing).

    .venv/bin/python benchmarks/denoise_subpixel.py [--scenes cornell-box dragon]
        [--scale 2] [--report]
"""

from __future__ import annotations

import argparse
import json
import os

import denoise as bench  # the scenes, R's cache, the method's setting
import numpy as np
from _report import machine_description, write_section

from styletrace.denoise import coverage, guides, oidn
from styletrace.denoise import expectation as X
from styletrace.frontends import api
from styletrace.gate import mi
from styletrace.lookdev.record import render_buffer
from styletrace.pipeline.passes import pass_seed

SIZE = 128  # the pixel protocol's
BUDGETS = ((8, 8), (64, 64))
SEEDS = (0, 1)
K, U = 64, 0.3


def finer_m(scene, buf, m: np.ndarray, emission: np.ndarray, scale: int) -> np.ndarray:
    """M at scale x the resolution: each camera sample's reflected children mean binned by its
    film position."""
    a = buf.arrays
    found = a["slot"] >= 0
    h, w = m.shape[:2]
    fw, fh = w * scale, h * scale
    uv = X.raster(scene, a["p"][:, found]) * scale
    sub = np.clip(np.floor(uv[:, 1]), 0, fh - 1).astype(np.int64) * fw + np.clip(
        np.floor(uv[:, 0]), 0, fw - 1
    ).astype(np.int64)
    vals = X.reflected(buf, emission)[found]
    count = np.bincount(sub, minlength=fw * fh).astype(np.float64)
    out = np.stack([np.bincount(sub, weights=vals[:, c], minlength=fw * fh) for c in range(3)], -1)
    out /= np.maximum(count, 1.0)[:, None]
    idx = np.arange(fw * fh)
    own_pixel = (idx // fw // scale) * w + (idx % fw) // scale
    out[count == 0] = m.reshape(-1, 3)[own_pixel[count == 0]]
    return out.reshape(fh, fw, 3).astype(np.float32)


def image(name, style, spp, n, seed, scale) -> np.ndarray:
    scene = bench.load(name, SIZE)
    integ = api.make_integrator(style=style, inner=n)
    buf = render_buffer(scene, spp=spp, seed=seed, integrator=integ)
    _, emission = X._own(scene, buf)
    m = X.expectation(buf, emission)
    if scale == 1:
        at, g, fine = scene, guides.first_hit(scene, spp, pass_seed(seed, 0)), m
    else:
        at = bench.load(name, SIZE * scale)
        g = guides.first_hit(at, max(1, spp // scale**2) * 4, pass_seed(seed, 0))
        fine = finer_m(scene, buf, m, emission, scale)
    d = X.below_resolution(
        oidn.denoise_oidn(fine, g.albedo, g.normal, "high", guides.to_sensor(at)), fine
    )
    field = X.Field(d, g, float(np.linalg.norm(np.asarray(scene.bbox().extents()))))
    field.spread = mi.Float(
        np.ascontiguousarray(X.spread(buf, emission, U).ravel(), dtype=np.float32)
    )
    return np.asarray(coverage.points(scene, integ, field, K, seed, scale).image, dtype=np.float64)[
        ..., :3
    ]


READING = (
    "Reading: at 64x the children, D at twice the resolution lowers the floor on every pair, most "
    "on the dragon "
    "(64% and 60% less), whose relief varies inside pixels at 128x128: D's one value per pixel is "
    "the largest part "
    "of the floor there. At the chosen budget (8 spp, n = 8) it lowers the dragon's MSE by 31% "
    "and 32% and the "
    "Cornell box's cel by 23%, but raises the Cornell box's hatching by 15%: a quarter of the "
    "samples per bin make "
    "the sub-pixel M noisier, and hatching's line density follows D below the pixel. Not adopted: "
    "on the Cornell "
    "box, where settings are chosen, the mean of the two styles' ratios would gain about 7% "
    "before OIDN's cost on "
    "4x the pixels (about +0.1 s on the setting's 0.43 s at 128x128, from the 512x512 timing's 2 "
    "us a pixel: "
    "+23% time, and the fixed counts' envelope falls about as time^-0.64 there, so about -12% on "
    "a ratio). What "
    "it shows is where the floor is and what would lower it: a D "
    "that resolves E[L] below the pixel at low sample counts."
)


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--scenes", nargs="*", default=["cornell-box", "dragon"])
    ap.add_argument("--scale", type=int, default=2)
    ap.add_argument("--report", action="store_true", help="only write the section from the cache")
    args = ap.parse_args()
    cache = os.path.join(bench.CACHE, f"denoise_subpixel_{args.scale}.json")
    if args.report:
        with open(cache) as f:
            results = json.load(f)
    else:
        results = []
        for name in args.scenes:
            ref = np.load(os.path.join(bench.CACHE, f"denoise_pixel_images_{name}_{SIZE}.npz"))
            for style in bench.PIXEL_STYLES:
                r = ref[f"{style}|reference"].astype(np.float64)
                for spp, n in BUDGETS:
                    mse = [
                        float(
                            np.mean(
                                [
                                    np.mean((image(name, style, spp, n, seed, s) - r) ** 2)
                                    for seed in SEEDS
                                ]
                            )
                        )
                        for s in (1, args.scale)
                    ]
                    print(
                        f"{name} {style} spp={spp} n={n}: D per pixel {mse[0]:.3e}, D at "
                        f"{args.scale}x {mse[1]:.3e}",
                        flush=True,
                    )
                    results.append([name, style, spp, n, *mse])
        os.makedirs(bench.CACHE, exist_ok=True)
        with open(cache, "w") as f:
            json.dump(results, f)
    rows = [
        f"| {name} | {style} | {spp} | {n} | {one:.3e} | {fine:.3e} | {fine / one:.2f} |"
        for name, style, spp, n, one, fine in results
    ]
    body = "\n".join(
        [
            "## Denoising: D below the pixel (experiment, `benchmarks/denoise_subpixel.py`)",
            "",
            __doc__.split("\n\n")[1].replace("\n", " "),
            "",
            f"| scene | style | spp | n | MSE, D per pixel | MSE, D at {args.scale}x | ratio |",
            "|---|---|---:|---:|---:|---:|---:|",
            *rows,
            "",
            READING,
            "",
            machine_description(),
        ]
    )
    write_section("denoise_subpixel", body)


if __name__ == "__main__":
    main()
