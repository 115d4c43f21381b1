"""Speed of `stylized` in scenes with participating media against Mitsuba's own `volpath`.

Two scenes at 128x128: a chromatic homogeneous fog inside a glass sphere, and a heterogeneous
density grid in a `null` cube (both on a floor under an area light, a point light and a sky).
`stylized` (identity, and cel) at S camera samples with n inner samples per stylized vertex is timed
against `volpath` at S*n samples per pixel (the same number of light paths). Each configuration is
warmed up once (kernel compilation), then timed `--runs` times; the table gives medians.

    .venv/bin/python benchmarks/media_speed.py [--runs 3]
"""
from __future__ import annotations

import argparse

import numpy as np
from _report import machine_description, write_section
from render_speed import timed

import styletrace
from styletrace.frontends.api import make_integrator
from styletrace.gate import mi

styletrace.init()  # first: it points Dr.Jit at a working libLLVM

RES = 128
S, N = 8, 8
T = mi.ScalarTransform4f


def lit(d):
    d["sensor"] = {
        "type": "perspective",
        "fov": 40,
        "sampler": {"type": "independent"},
        "to_world": T().look_at(origin=[0, 0.6, 4.0], target=[0, 0.1, 0], up=[0, 1, 0]),
        "film": {"type": "hdrfilm", "width": RES, "height": RES, "rfilter": {"type": "box"}},
    }
    floor = T().translate([0, -1, 0]) @ T().rotate([1, 0, 0], -90) @ T().scale(4)
    d["floor"] = {
        "type": "rectangle",
        "to_world": floor,
        "bsdf": {"type": "diffuse", "reflectance": {"type": "rgb", "value": [0.6, 0.6, 0.6]}},
    }
    light = T().translate([0.5, 2.5, 0.5]) @ T().rotate([1, 0, 0], 90) @ T().scale(0.8)
    d["light"] = {
        "type": "rectangle",
        "to_world": light,
        "emitter": {"type": "area", "radiance": {"type": "rgb", "value": [5.0, 4.5, 4.0]}},
    }
    d["point"] = {
        "type": "point",
        "position": [-1.5, 1.5, 1.5],
        "intensity": {"type": "rgb", "value": [3.0, 3.0, 3.0]},
    }
    d["env"] = {"type": "constant", "radiance": {"type": "rgb", "value": [0.3, 0.35, 0.4]}}
    return mi.load_dict(d)


def fog_ball():
    return lit(
        {
            "type": "scene",
            "fog": {
                "type": "homogeneous",
                "sigma_t": {"type": "rgb", "value": [0.5, 0.7, 1.0]},
                "scale": 2.0,
                "albedo": {"type": "rgb", "value": [0.9, 0.7, 0.5]},
            },
            "ball": {
                "type": "sphere",
                "radius": 0.9,
                "bsdf": {"type": "dielectric", "int_ior": 1.33},
                "interior": {"type": "ref", "id": "fog"},
            },
        }
    )


def smoke_cube():
    x = np.linspace(-1, 1, 16)
    zz, yy, xx = np.meshgrid(x, x, x, indexing="ij")
    density = (np.clip(1.2 - (xx**2 + yy**2 + zz**2), 0.0, None) * 3.0)[..., None].astype(
        np.float32
    )
    box = T().scale(0.8)
    return lit(
        {
            "type": "scene",
            "smoke": {
                "type": "heterogeneous",
                "albedo": 0.8,
                "phase": {"type": "hg", "g": 0.4},
                "sigma_t": {
                    "type": "gridvolume",
                    "grid": mi.VolumeGrid(density),
                    "to_world": box @ T().translate([-1, -1, -1]) @ T().scale(2),
                },
            },
            "cube": {
                "type": "cube",
                "to_world": box,
                "bsdf": {"type": "null"},
                "interior": {"type": "ref", "id": "smoke"},
            },
        }
    )


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--runs", type=int, default=3)
    args = ap.parse_args()

    rows = []
    for name, make in (
        ("fog in a glass sphere", fog_ball),
        ("density grid in a null cube", smoke_cube),
    ):
        scene = make()
        t_ref, _ = timed(scene, mi.load_dict({"type": "volpath"}), S * N, args.runs)
        for style in ("identity", "cel"):
            t_ours, _ = timed(scene, make_integrator(style, inner=N), S, args.runs)
            rows.append((name, style, t_ours, t_ref, t_ours / t_ref))
        print(rows[-2:], flush=True)

    lines = [
        "## Participating media: stylized vs Mitsuba `volpath` (`benchmarks/media_speed.py`)",
        "",
        f"Machine: {machine_description()}.",
        "",
        f"{RES}x{RES}, `stylized` at S={S} camera samples x n={N} inner samples vs `volpath` at "
        f"{S * N} spp "
        f"(same number of light paths), max_depth unbounded, median of {args.runs} runs after one "
        f"warm-up run.",
        "",
        "| scene | style | stylized (s) | volpath (s) | ratio |",
        "|---|---|---|---|---|",
    ]
    for name, style, t_o, t_r, ratio in rows:
        lines.append(f"| {name} | {style} | {t_o:.2f} | {t_r:.2f} | {ratio:.3f} |")
    write_section("media_speed", "\n".join(lines))
    print("\n".join(lines))


if __name__ == "__main__":
    main()
