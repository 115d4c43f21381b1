"""Light portals: the environment sampled through a window (kernel/portal_guide.py) against the
environment's own sampling, at equal samples and at equal time.

Two interiors lit only by an environment through windows, built here:
- room: 5 x 2.6 x 5 m, one window 1.4 x 1.1 m in its left wall, a table and a cabinet, under a sky
  map (a gradient with a small bright sun that shines through the window onto the table and the
  floor, `sky_map`): the map's own sampling already finds the sun, the portal the rest of the sky;
- hall: 3 x 3 x 10 m, two windows 0.8 x 0.8 m high in its side walls at the far end, under a
  uniform sky (`constant`); the camera looks down the hall from the other end.
For each, the identity style (one path per camera sample, inner=1) renders RUNS seeded images at
SPP with a `portal` over every window and without; the error is the mean squared error against
Mitsuba's `path` without portals at REF_SPP (16 seeded parts; their variance of the mean, ref var,
is taken off every MSE in the ratios). Both are unbiased, so MSE x seconds compares them at equal
time (seconds: the median wall time of a render; the configurations take turns seed by seed). The
share of light samples sent through the portals (`portal_guide.SHARE`, q) was set to 0.5 from
Cycles' split before measuring; the q columns check it on the room and show the hall alike: MSE x
seconds at q = 0.25 and 0.75 over q = 0.5's.

    .venv/bin/python benchmarks/portals.py            # the table, into BENCHMARKS.md
    .venv/bin/python benchmarks/portals.py --print    # the table, printed only
"""
from __future__ import annotations

import argparse
import os
import statistics
import sys
import time

import numpy as np
from _report import machine_description, write_section

import styletrace
from styletrace.frontends.api import make_integrator, passes
from styletrace.gate import mi
from styletrace.kernel import portal_guide

sys.path.insert(0, os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))),
                                "tests"))
from helpers.window_room import rectangle as rect  # noqa: E402  (the tests' window rooms')

styletrace.init()

RES, SPP, RUNS, REF_SPP = 64, 64, 6, 8192
#: the shares compared with the default
SHARES = (0.25, 0.75)
T = mi.ScalarTransform4f


def diffuse(rgb, two_sided=True) -> dict:
    bsdf = {"type": "diffuse", "reflectance": {"type": "rgb", "value": list(rgb)}}
    return {"type": "twosided", "bsdf": bsdf} if two_sided else bsdf




def box(lo, hi, bsdf) -> dict:
    lo, hi = np.asarray(lo, float), np.asarray(hi, float)
    return {"type": "cube", "to_world": T().translate((lo + hi) / 2) @ T().scale((hi - lo) / 2),
            "bsdf": bsdf}


#: turns that take a rectangle's +z to +x, -x (its local x then runs along -z, +z)
TO_PLUS_X, TO_MINUS_X = [([0, 1, 0], 90)], [([0, 1, 0], -90)]


def wall_with_window(x, turns, z_span, y_span, window_z, window_y, bsdf, name) -> dict:
    """A wall in the plane x = `x` spanning z_span x y_span with a rectangular hole, as four
    rectangles {name_*: shape}."""
    (z0, z1), (y0, y1) = z_span, y_span
    (wz0, wz1), (wy0, wy1) = window_z, window_y

    def piece(za, zb, ya, yb):
        return rect([x, (ya + yb) / 2, (za + zb) / 2], turns, ((zb - za) / 2, (yb - ya) / 2), bsdf)

    return {f"{name}_below": piece(z0, z1, y0, wy0), f"{name}_above": piece(z0, z1, wy1, y1),
            f"{name}_side0": piece(z0, wz0, wy0, wy1), f"{name}_side1": piece(wz1, z1, wy0, wy1)}


def portal(x, turns, window_z, window_y) -> dict:
    """The portal over a window of a wall at x, facing where `turns` take +z (into the room)."""
    (wz0, wz1), (wy0, wy1) = window_z, window_y
    return {"type": "portal", "to_world": T().translate([x, (wy0 + wy1) / 2, (wz0 + wz1) / 2])
            @ T().rotate(*turns[0]) @ T().scale([(wz1 - wz0) / 2, (wy1 - wy0) / 2, 1.0])}


def sensor(res, origin, target, fov=70) -> dict:
    return {"type": "perspective", "fov": fov,
            "to_world": T().look_at(origin=origin, target=target, up=[0, 1, 0]),
            "sampler": {"type": "independent"},
            "film": {"type": "hdrfilm", "width": res, "height": res, "rfilter": {"type": "box"}}}


def sky_map() -> mi.Bitmap:
    """64 x 128: blue overhead to white at the horizon, a dim ground, a 3 x 3 texel sun of
    radiance 500 about 30 degrees up (turned by `room` to shine in through its window)."""
    h, w = 64, 128
    theta = (np.arange(h) + 0.5) / h * np.pi
    img = np.zeros((h, w, 3), np.float32)
    up = np.clip(np.cos(theta), 0, 1)[:, None]
    img[:] = (0.25 + 0.9 * (1 - up) * np.array([0.9, 0.95, 1.0]) + up * np.array([0.3, 0.5, 1.0]))[
        :, None, :]
    img[theta > np.pi / 2] = [0.15, 0.13, 0.1]
    img[20:23, 95:98] = 500.0
    return mi.Bitmap(img)


def room(res, portals=True) -> dict:
    """Interior A (module docstring)."""
    wall, floor = diffuse([0.7, 0.68, 0.62]), diffuse([0.45, 0.35, 0.25])
    wz, wy = (-0.7, 0.7), (0.9, 2.0)
    d = {"type": "scene", "sensor": sensor(res, [2.2, 1.6, 2.2], [-1.5, 0.8, -1.2]),
         "floor": rect([0, 0, 0], [([1, 0, 0], -90)], (2.5, 2.5), floor),
         "ceiling": rect([0, 2.6, 0], [([1, 0, 0], 90)], (2.5, 2.5), wall),
         "back": rect([0, 1.3, -2.5], [], (2.5, 1.3), wall),
         "front": rect([0, 1.3, 2.5], [([0, 1, 0], 180)], (2.5, 1.3), wall),
         "right": rect([2.5, 1.3, 0], TO_MINUS_X, (2.5, 1.3), wall),
         "table": box([-0.9, 0.7, -0.9], [0.5, 0.78, 0.3], diffuse([0.5, 0.3, 0.15])),
         "leg": box([-0.3, 0.0, -0.4], [-0.1, 0.7, -0.2], diffuse([0.5, 0.3, 0.15])),
         "cabinet": box([1.6, 0.0, -2.5], [2.5, 1.8, -1.9], diffuse([0.2, 0.3, 0.45])),
         "sky": {"type": "envmap", "bitmap": sky_map(),
                 "to_world": T().rotate([0, 1, 0], 15)},
         **wall_with_window(-2.5, TO_PLUS_X, (-2.5, 2.5), (0.0, 2.6), wz, wy, wall, "left")}
    if portals:
        d["window"] = portal(-2.5, TO_PLUS_X, wz, wy)
    return d


def hall(res, portals=True) -> dict:
    """Interior B (module docstring)."""
    wall = diffuse([0.65, 0.65, 0.65])
    wz, wy = (-4.6, -3.8), (1.8, 2.6)  # near the far end z = -5
    d = {"type": "scene", "sensor": sensor(res, [0.0, 1.6, 4.8], [0.0, 1.0, -5.0], fov=60),
         "floor": rect([0, 0, 0], [([1, 0, 0], -90)], (1.5, 5.0), diffuse([0.4, 0.4, 0.4])),
         "ceiling": rect([0, 3.0, 0], [([1, 0, 0], 90)], (1.5, 5.0), wall),
         "far": rect([0, 1.5, -5.0], [], (1.5, 1.5), wall),
         "near": rect([0, 1.5, 5.0], [([0, 1, 0], 180)], (1.5, 1.5), wall),
         "bench": box([-0.4, 0.0, -2.0], [0.4, 0.5, 0.0], diffuse([0.6, 0.4, 0.3])),
         "sky": {"type": "constant", "radiance": {"type": "rgb", "value": [1.0, 0.95, 0.9]}},
         **wall_with_window(-1.5, TO_PLUS_X, (-5.0, 5.0), (0.0, 3.0), wz, wy, wall, "left"),
         **wall_with_window(1.5, TO_MINUS_X, (-5.0, 5.0), (0.0, 3.0), wz, wy, wall, "right")}
    if portals:
        d["window_left"] = portal(-1.5, TO_PLUS_X, wz, wy)
        d["window_right"] = portal(1.5, TO_MINUS_X, wz, wy)
    return d


def render(scene, integrator, spp, seed):
    return list(passes(scene, integrator, spp, seed=seed))[-1].image[..., :3].astype(np.float64)


def reference(scene_dict, ref_spp):
    """Mitsuba's `path` at ref_spp as 16 seeded parts: (their mean, the variance of that mean
    averaged over the pixel channels)."""
    scene = mi.load_dict(scene_dict)
    path = mi.load_dict({"type": "path"})
    parts = np.stack([np.asarray(mi.render(scene, integrator=path, spp=ref_spp // 16,
                                           seed=10_000 + k), np.float64) for k in range(16)])
    return parts.mean(axis=0), float(np.mean(parts.var(axis=0, ddof=1)) / len(parts))


def measure(configs, ref, spp, runs):
    """{name: (mean MSE against ref over `runs` seeds, median seconds per render)} of the identity
    on each (scene dict, share of light samples through the portals) of `configs` {name: ...}; the
    configurations take turns seed by seed, so that other work on the machine slows them alike."""
    default = portal_guide.SHARE
    loaded = {name: (mi.load_dict(d), q) for name, (d, q) in configs.items()}
    integrator = make_integrator("identity", inner=1)
    errs = {name: [] for name in configs}
    times = {name: [] for name in configs}
    try:
        for k in [None, *range(runs)]:  # None: compile every kernel first
            for name, (scene, q) in loaded.items():
                portal_guide.SHARE = q
                t = time.perf_counter()
                img = render(scene, integrator, spp, 99 if k is None else k)
                if k is not None:
                    times[name].append(time.perf_counter() - t)
                    errs[name].append(float(np.mean((img - ref) ** 2)))
    finally:
        portal_guide.SHARE = default
    return {name: (statistics.mean(errs[name]), statistics.median(times[name]))
            for name in configs}


def table(res, spp, runs, ref_spp):
    rows = []
    q0 = portal_guide.SHARE
    for name, build in (("room: one window, sky map with a sun", room),
                        ("hall: two small windows, uniform sky", hall)):
        ref, ref_var = reference(build(res, portals=False), ref_spp)
        configs = {"off": (build(res, portals=False), q0), q0: (build(res, portals=True), q0)}
        configs.update({q: (build(res, portals=True), q) for q in SHARES})
        got = measure(configs, ref, spp, runs)
        cost = {c: max(mse - ref_var, 0.0) * s for c, (mse, s) in got.items()}
        (off, s_off), (on, s_on) = got["off"], got[q0]
        rows.append(f"| {name} | {ref_var:.1e} | {off:.3e} | {s_off:.2f} | {on:.3e} | "
                    f"{s_on:.2f} | {(on - ref_var) / (off - ref_var):.2f} | "
                    f"{cost[q0] / cost['off']:.2f} | "
                    + " | ".join(f"{cost[q] / cost[q0]:.2f}" for q in SHARES) + " |")
        print(rows[-1], flush=True)
    return rows


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--print", action="store_true", help="print the table, leave "
                        "BENCHMARKS.md alone")
    parser.add_argument("--res", type=int, default=RES)
    parser.add_argument("--spp", type=int, default=SPP)
    parser.add_argument("--runs", type=int, default=RUNS)
    parser.add_argument("--ref-spp", type=int, default=REF_SPP)
    args = parser.parse_args()
    start = time.perf_counter()
    rows = table(args.res, args.spp, args.runs, args.ref_spp)
    print(f"{time.perf_counter() - start:.0f} s in all")
    if args.print:
        return
    q = ", ".join(f"q = {v}" for v in SHARES)
    body = "\n".join([
        "## Light portals (`benchmarks/portals.py`)",
        "",
        f"Identity style, inner=1, {args.res}x{args.res}, {args.spp} spp, mean over {args.runs} "
        f"seeds, with a `portal` over every window (q = {portal_guide.SHARE} of the environment's "
        "light samples through the portals) and without; reference: Mitsuba `path` without "
        f"portals at {args.ref_spp} spp in 16 seeded parts (ref var: the variance of their mean, "
        "taken off every MSE in the ratios). Both are unbiased: MSE x s compares them at equal "
        f"time. Last columns: MSE x s at {q} over q = {portal_guide.SHARE}'s, below 1 where "
        "that share would do better (q was set to Cycles' even split before measuring and "
        "checked on the room; the hall is reported alike; docs/design/portals.md). Scenes built "
        "in the script (its docstring).",
        "",
        "| interior | ref var | MSE off | s | MSE portals | s | MSE portals / off "
        "| (MSE x s) portals / off | " + " | ".join(f"(MSE x s) q={v} / q={portal_guide.SHARE}"
                                                  for v in SHARES) + " |",
        "|---|---|---|---|---|---|---|---|" + "---|" * len(SHARES),
        *rows,
        "",
        machine_description(),
    ])
    write_section("portals", body)


if __name__ == "__main__":
    main()
