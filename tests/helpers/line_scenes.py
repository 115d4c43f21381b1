"""The scene of the lifted-lines tests (tests/kernel): a box seen directly (left) and, with a plane behind the
camera, in a mirror ball (right; `flat`: a flat mirror facing the camera, turned 8 degrees, instead)."""
import mitsuba as mi

RES = 64


def line_scene(alpha=0.0, flat=False, res=RES, light=None) -> dict:
    """The scene as a dict; `light`: a constant environment's grey radiance (None: no light at all)."""
    T = mi.ScalarTransform4f
    ball = {"type": "conductor", "material": "none"} if alpha == 0 else \
        {"type": "roughconductor", "material": "none", "distribution": "ggx", "alpha": alpha}
    grey = {"type": "diffuse"}
    d = {
        "type": "scene",
        "sensor": {"type": "perspective", "fov": 40,
                   "to_world": T().look_at(origin=[0, 0, 6], target=[0, 0, 0], up=[0, 1, 0]),
                   "film": {"type": "hdrfilm", "width": res, "height": res, "rfilter": {"type": "box"}}},
        "box": {"type": "cube", "bsdf": grey,
                "to_world": T().translate([-1.4, 0, 0]) @ T().rotate([1, 1, 0], 30) @ T().scale(0.7)},
        "ball": {"type": "rectangle", "bsdf": ball,
                 "to_world": T().translate([1.4, 0, 0]) @ T().rotate([0, 1, 0], -8) @ T().scale(1.0)} if flat else
                {"type": "sphere", "center": [1.4, 0, 0], "radius": 1.1, "bsdf": ball},
        "back": {"type": "rectangle", "bsdf": grey,
                 "to_world": T().translate([1.0, 0.5, 8]) @ T().rotate([0, 1, 0], 180) @ T().scale([1.5, 1.0, 1])},
    }
    if light is not None:
        d["light"] = {"type": "constant", "radiance": {"type": "rgb", "value": [light] * 3}}
    return d
