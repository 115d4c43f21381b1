"""Scenes with many small lights for benchmarks/emitter_sampling.py: a furnished room with 32 lamps
(measured) and a corridor with 18 (the one spatial selection's constant was chosen on). Both are
built from a fixed seed, so every run renders the same scene.
"""
from __future__ import annotations

import numpy as np

from styletrace.gate import mi

T = mi.ScalarTransform4f


def _sensor(res: int, origin, target, fov: float) -> dict:
    return {
        "type": "perspective",
        "fov": fov,
        "to_world": T().look_at(origin=origin, target=target, up=[0, 1, 0]),
        "sampler": {"type": "independent"},
        "film": {"type": "hdrfilm", "width": res, "height": res, "rfilter": {"type": "box"}},
    }


def _grey(value: float, rgb=None) -> dict:
    colour = list(rgb) if rgb is not None else [value] * 3
    return {"type": "twosided",
            "bsdf": {"type": "diffuse", "reflectance": {"type": "rgb", "value": colour}}}


def _panel(center, half: float, radiance: float, facing: str) -> dict:
    """A square one-sided area light of half-width `half` at `center`, emitting towards -Y
    ('down'), +X, -X, +Z or -Z."""
    turn = {"down": T().rotate([1, 0, 0], 90), "+x": T().rotate([0, 1, 0], 90),
            "-x": T().rotate([0, 1, 0], -90), "+z": T(), "-z": T().rotate([0, 1, 0], 180)}[facing]
    return {
        "type": "rectangle",
        "to_world": T().translate(list(center)) @ turn @ T().scale(half),
        "bsdf": {"type": "diffuse", "reflectance": {"type": "rgb", "value": [0.0] * 3}},
        "emitter": {"type": "area", "radiance": {"type": "rgb", "value": [radiance] * 3}},
    }


def _box(lo, hi, bsdf: dict) -> dict:
    lo, hi = np.asarray(lo, float), np.asarray(hi, float)
    c, h = (lo + hi) / 2, (hi - lo) / 2
    return {"type": "cube", "to_world": T().translate(c.tolist()) @ T().scale(h.tolist()),
            "bsdf": bsdf}


def _walls(d: dict, x: float, y: float, z0: float, z1: float) -> None:
    """Floor, ceiling and four walls of the box [-x, x] x [0, y] x [z0, z1] (two-sided)."""
    cz, hz = (z0 + z1) / 2, (z1 - z0) / 2
    d["floor"] = {"type": "rectangle", "bsdf": _grey(0.5),
                  "to_world": T().translate([0, 0, cz]) @ T().rotate([1, 0, 0], -90)
                  @ T().scale([x, hz, 1])}
    d["ceiling"] = {"type": "rectangle", "bsdf": _grey(0.8),
                    "to_world": T().translate([0, y, cz]) @ T().rotate([1, 0, 0], 90)
                    @ T().scale([x, hz, 1])}
    for name, at, turn, scale in (
        ("wall_left", [-x, y / 2, cz], T().rotate([0, 1, 0], 90), [hz, y / 2, 1]),
        ("wall_right", [x, y / 2, cz], T().rotate([0, 1, 0], -90), [hz, y / 2, 1]),
        ("wall_back", [0, y / 2, z0], T(), [x, y / 2, 1]),
        ("wall_front", [0, y / 2, z1], T().rotate([0, 1, 0], 180), [x, y / 2, 1]),
    ):
        d[name] = {"type": "rectangle", "bsdf": _grey(0.65),
                   "to_world": T().translate(at) @ turn @ T().scale(scale)}


def lamp_room(res: int) -> dict:
    """An 8 x 3 x 6 m room, half split by a partition, with a table and two cabinets, lit by 20
    small ceiling panels, 4 wall panels and 8 bulbs whose powers span two decades."""
    rng = np.random.default_rng(46)
    d = {"type": "scene", "sensor": _sensor(res, [-3.6, 1.7, 2.6], [1.5, 0.7, -1.5], 75)}
    _walls(d, 4.0, 3.0, -3.0, 3.0)
    d["partition"] = _box([0.4, 0.0, -3.0], [0.55, 2.4, 0.8], _grey(0.7))
    d["table"] = _box([-2.5, 0.7, -1.6], [-0.8, 0.76, -0.4], _grey(0.6, [0.55, 0.4, 0.3]))
    d["cabinet_a"] = _box([2.2, 0.0, 1.8], [3.6, 1.9, 2.7], _grey(0.6, [0.3, 0.45, 0.6]))
    d["cabinet_b"] = _box([-3.9, 0.0, -2.9], [-3.0, 1.2, -1.8], _grey(0.6, [0.6, 0.6, 0.35]))
    for k, (x, z) in enumerate((x, z) for x in (-3.2, -1.6, 0.0, 1.6, 3.2)
                               for z in (-2.2, -0.7, 0.8, 2.2)):
        half = float(rng.uniform(0.06, 0.18))
        watts = float(np.exp(rng.uniform(np.log(0.5), np.log(50.0))))
        # radiance L of a square emitting Phi = pi L A
        d[f"panel_{k:02d}"] = _panel([x, 2.99, z], half, watts / (np.pi * 4 * half * half),
                                     "down")
    for k, (at, facing) in enumerate((([-3.99, 2.0, 0.0], "+x"), ([3.99, 2.0, -1.0], "-x"),
                                      ([1.0, 1.8, -2.99], "+z"), ([-1.5, 1.8, 2.99], "-z"))):
        watts = float(np.exp(rng.uniform(np.log(0.5), np.log(20.0))))
        d[f"sconce_{k}"] = _panel(at, 0.08, watts / (np.pi * 4 * 0.08 * 0.08), facing)
    for k in range(8):
        at = [float(rng.uniform(-3.5, 3.5)), float(rng.uniform(0.9, 2.2)),
              float(rng.uniform(-2.5, 2.5))]
        watts = float(np.exp(rng.uniform(np.log(0.5), np.log(30.0))))
        d[f"bulb_{k}"] = {"type": "point", "position": at,
                          "intensity": {"type": "rgb", "value": [watts / (4 * np.pi)] * 3}}
    return d


def lamp_corridor(res: int) -> dict:
    """A 2 x 2.5 x 20 m corridor with doors of light: 12 ceiling panels, 4 wall sconces, 2 bulbs
    and a few crates; the camera looks down its length."""
    rng = np.random.default_rng(7)
    d = {"type": "scene", "sensor": _sensor(res, [0.5, 1.5, -0.4], [-0.3, 1.0, -12.0], 60)}
    _walls(d, 1.0, 2.5, -20.0, 0.0)
    for k in range(4):
        z = -3.0 - 4.0 * k
        side = -1 if k % 2 else 1
        d[f"crate_{k}"] = _box([side * 0.9 - 0.3, 0.0, z - 0.4], [side * 0.9 + 0.3, 0.8, z + 0.4],
                               _grey(0.6, [0.5, 0.35, 0.2]))
    for k in range(12):
        watts = float(np.exp(rng.uniform(np.log(1.0), np.log(40.0))))
        half = float(rng.uniform(0.1, 0.25))
        d[f"panel_{k:02d}"] = _panel([0.0, 2.49, -1.0 - 1.6 * k], half,
                                     watts / (np.pi * 4 * half * half), "down")
    for k in range(4):
        side = -1 if k % 2 else 1
        watts = float(np.exp(rng.uniform(np.log(0.5), np.log(10.0))))
        d[f"sconce_{k}"] = _panel([-side * 0.99, 1.7, -2.0 - 4.5 * k], 0.07,
                                  watts / (np.pi * 4 * 0.07 * 0.07), "+x" if side > 0 else "-x")
    for k in range(2):
        watts = float(np.exp(rng.uniform(np.log(1.0), np.log(20.0))))
        d[f"bulb_{k}"] = {"type": "point", "position": [0.3 - 0.6 * k, 1.2, -6.0 - 7.0 * k],
                          "intensity": {"type": "rgb", "value": [watts / (4 * np.pi)] * 3}}
    return d
