"""Small scenes with participating media and the comparison with Mitsuba's `volpath` that
tests/kernel/test_media*.py share: K independent renders per side at the same number of light
paths, the difference of the image means tested against its standard error (`mean_z`) and each 4
x 4 pixel block (`pixel_t_test`)."""
import numpy as np

from helpers.stats import mean_threshold, mean_z, pixel_t_test
from styletrace.frontends.api import passes
from styletrace.gate import mi

K, RES = 10, 24
SPP, INNER = 4, 4
Z_MAX = mean_threshold(K)
T = mi.ScalarTransform4f


def renders(scene, integrator, spp, seed0):
    return np.stack(
        [list(passes(scene, integrator, spp, seed=seed0 + k))[-1].image for k in range(K)]
    )


def assert_matches_volpath(scene, integrator, volpath=None, block=4):
    ours = renders(scene, integrator, SPP, 1000)
    ref = renders(scene, mi.load_dict({"type": "volpath", **(volpath or {})}), SPP * INNER, 5000)
    assert np.all(np.isfinite(ours))
    z = mean_z(ours, ref)
    assert np.all(np.abs(z) < Z_MAX), f"image means differ from volpath: z = {z}"
    tmax, thr, frac = pixel_t_test(ours, ref, 1e-3, block=block)
    assert tmax < thr, f"max |t| {tmax:.2f} over threshold {thr:.2f} ({frac:.3%} of blocks)"
    return z


def sensor(res, origin=(0, 0.6, 4.0), **extra):
    return {
        "type": "perspective",
        "fov": 40,
        "sampler": {"type": "independent"},
        "to_world": T().look_at(origin=list(origin), target=[0, 0.1, 0], up=[0, 1, 0]),
        "film": {"type": "hdrfilm", "width": res, "height": res, "rfilter": {"type": "box"}},
        **extra,
    }


def diffuse(rgb, styled=False):
    b = {"type": "diffuse", "reflectance": {"type": "rgb", "value": rgb}}
    return {"type": "styled", "style": "identity", "inner_samples": 2, "bsdf": b} if styled else b


def lit(d, env=True):
    """Floor, an area light above, a point light and (optionally) a constant environment."""
    floor = T().translate([0, -1, 0]) @ T().rotate([1, 0, 0], -90) @ T().scale(4)
    d["floor"] = {"type": "rectangle", "to_world": floor,
                  "bsdf": d.pop("floor_bsdf", diffuse([0.6, 0.6, 0.6]))}
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
    if env:
        d["env"] = {"type": "constant", "radiance": {"type": "rgb", "value": [0.3, 0.35, 0.4]}}
    return d


def fog_ball(res=RES, styled_floor=False, ior=1.33):
    """The issue's scene: a chromatic homogeneous medium inside a glass sphere."""
    return lit(
        {
            "type": "scene",
            "sensor": sensor(res),
            "fog": {
                "type": "homogeneous",
                "sigma_t": {"type": "rgb", "value": [0.5, 0.7, 1.0]},
                "scale": 2.0,
                "albedo": {"type": "rgb", "value": [0.9, 0.7, 0.5]},
            },
            "ball": {
                "type": "sphere",
                "radius": 0.9,
                "bsdf": {"type": "dielectric", "int_ior": ior},
                "interior": {"type": "ref", "id": "fog"},
            },
            "floor_bsdf": diffuse([0.6, 0.6, 0.6], styled_floor),
        }
    )


def smoke_cube(res=RES):
    """A heterogeneous medium (a 6^3 grid of densities) bounded by a `null` cube, anisotropic
    phase."""
    x = np.linspace(-1, 1, 6)
    zz, yy, xx = np.meshgrid(x, x, x, indexing="ij")
    density = np.clip(1.2 - (xx ** 2 + yy ** 2 + zz ** 2), 0.0, None) * 3.0
    grid = mi.VolumeGrid(density[..., None].astype(np.float32))
    box = T().scale(0.8)
    return lit(
        {
            "type": "scene",
            "sensor": sensor(res),
            "smoke": {
                "type": "heterogeneous",
                "albedo": 0.8,
                "phase": {"type": "hg", "g": 0.4},
                "sigma_t": {
                    "type": "gridvolume",
                    "grid": grid,
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


def foggy_room(res=RES):
    """The camera stands in a thin homogeneous fog that fills the whole scene (the sensor's
    medium)."""
    d = lit(
        {
            "type": "scene",
            "fog": {
                "type": "homogeneous",
                "sigma_t": 0.25,
                "albedo": {"type": "rgb", "value": [0.8, 0.8, 0.9]},
            },
            "ball": {"type": "sphere", "radius": 0.7, "bsdf": diffuse([0.7, 0.4, 0.2])},
        },
        env=False,
    )
    d["sensor"] = sensor(res, medium={"type": "ref", "id": "fog"})
    return d


SCENES = {"fog_ball": fog_ball, "smoke_cube": smoke_cube, "foggy_room": foggy_room}
