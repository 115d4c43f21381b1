"""docs/llat.png: LLaT's canonical lifting of tone and its lifted lines (docs/llat.md) beside the
world-anchored modes, in setups after "Lifting Lines and Tone" (West, Mukherjee, Yue 2026) Fig. 13
and 14.

Rows: (a) direct view, (b) flat perfect mirror, (c) curved glossy reflection (a GGX ball, roughness
0.01),
(d) depth of field (thin lens focused on the directly seen plane, the mirror out of focus),
(e) per-object tone fields (five objects, five hatching/halftone settings, one flipped inside
    reflections,
on a glossy floor). Columns: lift=canonical with line_mode lifted (shape-id and crease types, blue)
| lift=position with West 2021's cone (line_mode absorb, the same colour), both with line_depth 3.

    PYTHONPATH=src python docs/make_llat_figure.py [SIZE] [SPP]
"""
from __future__ import annotations

import os
import sys

import numpy as np

import styletrace

GREY = {"type": "diffuse", "reflectance": {"type": "rgb", "value": [0.6, 0.6, 0.6]}}


def styled(style: dict, lift: str) -> dict:
    return {"type": "styled", **style, "lift": lift, "bsdf": GREY}


def sensor(size, thin=False):
    import mitsuba as mi

    s = (
        {"type": "thinlens", "aperture_radius": 0.3, "focus_distance": 6.0}
        if thin
        else {"type": "perspective"}
    )
    return {
        **s,
        "fov": 40,
        "to_world": mi.ScalarTransform4f().look_at(
            origin=[0, 0, 6], target=[0, 0, 0], up=[0, 1, 0]
        ),
        "sampler": {"type": "independent"},
        "film": {"type": "hdrfilm", "width": size, "height": size, "rfilter": {"type": "box"}},
    }


def fig13(kind: str, lift: str, size: int) -> dict:
    import mitsuba as mi
    T = mi.ScalarTransform4f
    hatch = dict(
        style="hatching",
        sets=2,
        angle=30.0,
        spacing_px=7.0,
        u_min=0.02,
        u_max=0.35,
        inner_samples=8,
    )
    d = {
        "type": "scene",
        "sensor": sensor(size, thin=kind == "dof"),
        "direct": {
            "type": "rectangle",
            "bsdf": styled(hatch, lift),
            "to_world": T().translate([-1.6, 0, 0]) @ T().scale([1.3, 1.6, 1]),
        },
        "lamp": {
            "type": "point",
            "position": [1.0, 2.5, 5.0],
            "intensity": {"type": "rgb", "value": [15.0] * 3},
        },
    }
    if kind == "direct":
        return d
    d["far"] = {
        "type": "rectangle",
        "bsdf": styled(hatch, lift),
        "to_world": T().translate([4.5, 0, 0]) @ T().rotate([0, 1, 0], -90) @ T().scale([6, 6, 1]),
    }
    d["back"] = {"type": "rectangle", "bsdf": styled(hatch, lift),
                 "to_world": T().translate([0, 0, 9]) @ T().rotate([0, 1, 0], 180) @ T().scale(12)}
    if kind == "ball":
        d["reflector"] = {
            "type": "sphere",
            "center": [1.6, 0, 0],
            "radius": 1.2,
            "bsdf": {
                "type": "roughconductor",
                "material": "none",
                "distribution": "ggx",
                "alpha": 0.01,
            },
        }
    else:
        d["reflector"] = {
            "type": "rectangle",
            "bsdf": {"type": "conductor", "material": "none"},
            "to_world": T().translate([1.5, 0, 0])
            @ T().rotate([0, 1, 0], 45)
            @ T().scale([1.2, 1.6, 1]),
        }
    return d


def fig14(lift: str, size: int) -> dict:
    import mitsuba as mi
    T = mi.ScalarTransform4f
    base = dict(u_min=0.02, u_max=0.3, inner_samples=8)
    fields = [dict(style="hatching", sets=1, angle=0.0, spacing_px=6.0),
              dict(style="hatching", sets=2, angle=45.0, spacing_px=8.0),
              dict(style="halftone", spacing_px=7.0),
              dict(style="hatching", sets=1, angle=90.0, angle_reflected=0.0, spacing_px=5.0),
              dict(style="hatching", sets=3, angle=15.0, spacing_px=10.0)]
    d = {
        "type": "scene",
        "sensor": {
            **sensor(size),
            "to_world": T().look_at(origin=[0, 1.6, 6], target=[0, -0.3, 0], up=[0, 1, 0]),
        },
        "floor": {
            "type": "rectangle",
            "to_world": T().translate([0, -1, 0]) @ T().rotate([1, 0, 0], -90) @ T().scale(6),
            "bsdf": {
                "type": "roughconductor",
                "material": "none",
                "distribution": "ggx",
                "alpha": 0.02,
            },
        },
        "wall": {
            "type": "rectangle",
            "bsdf": styled(
                dict(style="hatching", sets=1, angle=60.0, spacing_px=9.0, **base), lift
            ),
            "to_world": T().translate([0, 0, -3]) @ T().scale(6),
        },
        "lamp": {
            "type": "point",
            "position": [0.5, 4.0, 3.0],
            "intensity": {"type": "rgb", "value": [25.0] * 3},
        },
    }
    for i, f in enumerate(fields):
        x = -2.4 + 1.2 * i
        d[f"obj{i}"] = {
            "type": "sphere" if i % 2 == 0 else "cube",
            "bsdf": styled({**f, **base}, lift),
            **(
                {"center": [x, -0.5, 0.0], "radius": 0.5}
                if i % 2 == 0
                else {
                    "to_world": T().translate([x, -0.55, 0.0])
                    @ T().rotate([0, 1, 0], 30)
                    @ T().scale(0.42)
                }
            ),
        }
    return d


#: the lines of each column: lifted (LLaT) beside the canonical tone, West's cone beside the
#: position mode
INK = "0.1,0.15,0.6"
LINES = {"canonical": dict(lines=True, line_mode="lifted", line_depth=3,
                           line_types=f"shape_id color={INK}; normal threshold=0.35 color={INK}"),
         "position": dict(lines=True, line_mode="absorb", line_depth=3, line_color=INK,
                          line_tests="silhouette,boundary,crease")}


def main(size: int = 160, spp: int = 32) -> None:
    styletrace.init()
    import mitsuba as mi

    from styletrace.frontends import api
    rows = []
    for kind in ("direct", "flat", "ball", "dof", "fig14"):
        row = []
        for lift in ("canonical", "position"):
            scene = mi.load_dict(fig14(lift, size) if kind == "fig14" else fig13(kind, lift, size))
            integ = api.make_integrator("identity", stylize="first_object_hit", **LINES[lift])
            row.append(api.render(scene, integrator=integ, spp=spp, seed=1)[..., :3])
        gap = np.ones((size, 4, 3), np.float32)
        rows.append(np.concatenate([row[0], gap, row[1]], axis=1))
    gap = np.ones((4, rows[0].shape[1], 3), np.float32)
    out = rows[0]
    for r in rows[1:]:
        out = np.concatenate([out, gap, r], axis=0)
    api.write_image(out, os.path.join(os.path.dirname(os.path.abspath(__file__)), "llat.png"))


if __name__ == "__main__":
    main(*map(int, sys.argv[1:3]))
