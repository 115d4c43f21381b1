"""Scenes of the LLaT tone tests (tests/tone): a pinhole camera at (0, 0, 6) looking down -z,
hatched planes seen directly (left of the image) and in a reflector or behind glass (right)."""
from __future__ import annotations

import numpy as np

from styletrace.frontends.api import make_integrator, passes
from styletrace.gate import mi

T = mi.ScalarTransform4f
RES = 128
GREY = {"type": "diffuse", "reflectance": {"type": "rgb", "value": [0.5, 0.5, 0.5]}}
# one hatch set whatever the brightness (u far below u_max): the pattern is all there is to measure
HATCH = dict(
    style="hatching",
    sets=1,
    angle=30.0,
    spacing_px=8.0,
    thickness=3.2,
    u_min=0.0,
    u_max=100.0,
    inner_samples=1,
)


def styled(style: dict, bsdf=GREY) -> dict:
    return {"type": "styled", **{k: v for k, v in style.items()}, "bsdf": bsdf}


def sensor(res=RES, fov=40.0, origin=(0, 0, 6), target=(0, 0, 0), **extra) -> dict:
    return {"type": "perspective", "fov": fov, **extra,
            "to_world": T().look_at(origin=list(origin), target=list(target), up=[0, 1, 0]),
            "sampler": {"type": "independent"},
            "film": {"type": "hdrfilm", "width": res, "height": res, "rfilter": {"type": "box"}}}


def reflector(kind: str = "mirror", alpha: float = 0.0) -> dict:
    """The BSDF of the reflector: a perfect mirror (reflectance 1), a rough conductor of
    reflectance 1 with GGX roughness alpha, or glass (a smooth dielectric, IOR 1.5)."""
    if kind == "glass":
        return {"type": "dielectric", "int_ior": 1.5, "ext_ior": 1.0}
    if alpha == 0.0:
        return {"type": "conductor", "material": "none"}
    return {"type": "roughconductor", "material": "none", "distribution": "ggx", "alpha": alpha}


def mirror_scene(
    style: dict,
    kind: str = "mirror",
    alpha: float = 0.0,
    res: int = RES,
    shape="flat",
    sensor_extra: dict | None = None,
    far_x: float = 4.5,
    width: float = 1.2,
) -> mi.Scene:
    """Left: a hatched plane at z = 0 facing the camera (distance 6). Right: a reflector at x =
    1.5 turned 45 degrees (normal (1, 0, 1)/sqrt 2), which sends the camera's rays towards +x,
    onto a second hatched plane at x = 4.5 facing -x: seen at a virtual distance of about 9, 1.5x
    the direct plane's. shape='ball': the reflector is a sphere of radius 1.2 at (1.6, 0, 0)
    instead (a convex mirror). far_x, width: the second plane's x and the reflector's half-width
    (a narrow reflector close to the plane keeps a glossy lobe's blur small). No light: the
    hatching draws one set whatever the brightness (HATCH), so only the pattern is seen."""
    d = {
        "type": "scene",
        "sensor": sensor(res, **(sensor_extra or {})),
        "direct": {
            "type": "rectangle",
            "bsdf": styled(style),
            "to_world": T().translate([-1.6, 0, 0]) @ T().scale([1.3, 1.6, 1]),
        },
        "far": {
            "type": "rectangle",
            "bsdf": styled(style),
            "to_world": T().translate([far_x, 0, 0])
            @ T().rotate([0, 1, 0], -90)
            @ T().scale([6, 6, 1]),
        },
    }
    if shape == "flat":
        d["reflector"] = {
            "type": "rectangle",
            "bsdf": reflector(kind, alpha),
            "to_world": T().translate([1.5, 0, 0])
            @ T().rotate([0, 1, 0], 45)
            @ T().scale([width, 1.6, 1]),
        }
    else:
        d["reflector"] = {
            "type": "sphere",
            "center": [1.6, 0, 0],
            "radius": 1.2,
            "bsdf": reflector(kind, alpha),
        }
        # the ball mostly reflects what lies behind the camera: a third hatched plane there, facing
        # it
        d["back"] = {
            "type": "rectangle",
            "bsdf": styled(style),
            "to_world": T().translate([0, 0, 9]) @ T().rotate([0, 1, 0], 180) @ T().scale(12),
        }
    return mi.load_dict(d)


def render(scene, spp=1, seed=0, **values) -> np.ndarray:
    integ = make_integrator(**{"stylize": "first_object_hit", "style": "identity", **values})
    *_, last = passes(scene, integ, spp, seed=seed)
    return np.asarray(last.image, dtype=np.float64)[..., :3]


def first_hit_mask(scene, name: str, erode: int = 2) -> np.ndarray:
    """Pixels whose centre ray first hits the shape with id `name`, shrunk by `erode` pixels
    (edges mix)."""
    sensor = scene.sensors()[0]
    w, h = (int(x) for x in sensor.film().crop_size())
    col, row = np.meshgrid(np.arange(w), np.arange(h))
    uv = mi.Point2f(
        ((col + 0.5) / w).ravel().astype(np.float32), ((row + 0.5) / h).ravel().astype(np.float32)
    )
    ray, _ = sensor.sample_ray(mi.Float(0.0), mi.Float(0.5), uv, mi.Point2f(0.5, 0.5))
    si = scene.ray_intersect(ray)
    import drjit as dr
    target = [s for s in scene.shapes() if s.id() == name][0]
    hit = np.array(si.is_valid()) & (
        np.array(dr.reinterpret_array(mi.UInt32, si.shape))
        == np.array(dr.reinterpret_array(mi.UInt32, mi.ShapePtr(target)))[0]
    )
    m = hit.reshape(h, w)
    for _ in range(erode):
        m = m & np.roll(m, 1, 0) & np.roll(m, -1, 0) & np.roll(m, 1, 1) & np.roll(m, -1, 1)
    return m
