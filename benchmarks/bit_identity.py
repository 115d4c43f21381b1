"""Bit-identity of renders across a refactoring: sha256 of tiny images, one per kernel
configuration.

    # print NAME SHA256 per configuration
    .venv/bin/python benchmarks/bit_identity.py
    # compare with a recorded run; exit 1 on a difference
    .venv/bin/python benchmarks/bit_identity.py --check FILE

Every configuration goes through `styletrace.frontends.api.passes` with a prebuilt integrator (the
lowest public seam, present before and after the render pipeline existed), so the hashes say whether
the kernel and the pass loop draw the same samples, not whether a front end merges settings the same
way. Sizes and counts are tiny: the point is the digest, not the picture.
"""
from __future__ import annotations

import hashlib
import os
import sys

import numpy as np

import styletrace
from styletrace.frontends import api

styletrace.init()

RES = 12
#: cel's levels when the digests were recorded (its default then; now the levels follow the scene)
CEL = dict(levels="0.4,0.95")
#: name -> (scene, spp, integrator property values)
CONFIGS = {
    "first_hit_cel": ("cornell-box", 2, dict(style="cel", inner_samples=4, **CEL)),
    "affine_contrast": (
        "cornell-box",
        2,
        dict(style="contrast", estimator="affine", inner_samples=2),
    ),
    "series_gamma": ("cornell-box", 2, dict(style="gamma", estimator="series", inner_samples=4)),
    "ustat_tie_dye": ("cornell-box", 2, dict(style="tie_dye", estimator="ustat", inner_samples=4)),
    "naive_tie_dye": ("cornell-box", 2, dict(style="tie_dye", estimator="naive", inner_samples=4)),
    "telescoping_reinhard": (
        "cornell-box",
        2,
        dict(style="reinhard", estimator="telescoping", inner_samples=4),
    ),
    "combined_gamma_sepia": (
        "cornell-box",
        2,
        dict(style="gamma+sepia", estimator="combined", inner_samples=4),
    ),
    "first_n_hits": (
        "cornell-box",
        2,
        dict(style="cel", stylize="first_n_hits", stylize_depth=2, inner_samples="3,2", **CEL),
    ),
    "first_object_hit_mixed": (
        "mixed",
        2,
        dict(style="identity", stylize="first_object_hit", inner_samples=2),
    ),
    "lines": ("lines", 2, dict(style="cel", inner_samples=2, lines=True, **CEL)),
    "reuse_pixels_refine": (
        "cornell-box",
        2,
        dict(style="cel", reuse="pixels", inner_samples="2:8", **CEL),
    ),
    "reuse_deep_world": (
        "cornell-box",
        2,
        dict(
            style="cel",
            reuse="pixels",
            reuse_deep="world",
            stylize="first_n_hits",
            stylize_depth=2,
            inner_samples="2,2",
            **CEL,
        ),
    ),
    "hide_emitters_depth3": (
        "cornell-box",
        2,
        dict(style="identity", max_depth=3, hide_emitters=True, inner_samples=2),
    ),
}


def media_scene() -> dict:
    """A small fog ball in a glass sphere, lit by an area light, a point light and a constant
    sky."""
    sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "tests"))
    from helpers.media import fog_ball
    return fog_ball(RES)


def digest(image: np.ndarray) -> str:
    return hashlib.sha256(np.ascontiguousarray(image, dtype=np.float32).tobytes()).hexdigest()


def run() -> dict[str, str]:
    out = {}
    for name, (scene, spp, values) in CONFIGS.items():
        # the sampler the digests were recorded with (the built-in scenes' default since issue 46
        # is `owen_sobol`)
        sc = api.load_scene(scene, RES, RES, sampler="independent")
        integrator = api.make_integrator_from(values)
        out[name] = digest(list(api.passes(sc, integrator, spp, seed=7))[-1].image)
        del sc
    sc = api.load_scene(media_scene())
    integrator = api.make_integrator_from(dict(style="cel", inner_samples=2, **CEL))
    out["media_cel"] = digest(list(api.passes(sc, integrator, 2, seed=7))[-1].image)
    return out


def main(argv: list[str]) -> int:
    found = run()
    if len(argv) == 2 and argv[0] == "--check":
        with open(argv[1]) as f:
            recorded = dict(line.split() for line in f if line.strip() and not line.startswith("#"))
        bad = [k for k in recorded if found.get(k) != recorded[k]]
        for k, v in found.items():
            print(f"{k:24s} {v}  {'same' if recorded.get(k) == v else 'DIFFERENT'}")
        return 1 if bad else 0
    for k, v in found.items():
        print(f"{k} {v}")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
