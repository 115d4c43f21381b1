"""Scenes for the look at defaults (docs/look.md): a caustic seen only through rare children, and
a room whose brightness range a window sets. Mitsuba scene dicts; import after
`styletrace.init()`."""
from styletrace.gate import mi

RES = 48


def grey(a):
    return {"type": "diffuse", "reflectance": {"type": "rgb", "value": [a, a, a]}}


def caustic_scene(res=RES, rfilter="gaussian"):
    """A floor under a dim sky; a lamp of radius 0.04 under an opaque shade, seen by the floor
    only in a mirror above it: next-event estimation never reaches it, BSDF samples rarely do,
    and then carry 2000 x albedo."""
    T = mi.ScalarTransform4f
    return {
        "type": "scene",
        "sensor": {
            "type": "perspective",
            "fov": 45,
            "to_world": T().look_at(origin=[0, 3, 4], target=[0, 0, 0], up=[0, 1, 0]),
            "film": {"type": "hdrfilm", "width": res, "height": res, "rfilter": {"type": rfilter}},
            "sampler": {"type": "independent", "sample_count": 4},
        },
        "floor": {
            "type": "rectangle",
            "to_world": T().rotate([1, 0, 0], -90).scale(3),
            "bsdf": grey(0.5),
        },
        "sky": {"type": "constant", "radiance": {"type": "rgb", "value": [0.3, 0.3, 0.3]}},
        "lamp": {
            "type": "sphere",
            "center": [0, 1.0, 0],
            "radius": 0.04,
            "emitter": {"type": "area", "radiance": {"type": "rgb", "value": [2000, 2000, 2000]}},
        },
        "shade": {
            "type": "disk",
            "to_world": T().translate([0, 0.9, 0]).rotate([1, 0, 0], -90).scale(0.25),
            "bsdf": grey(0.2),
        },
        "mirror": {
            "type": "rectangle",
            "to_world": T().translate([0, 2.0, 0]).rotate([1, 0, 0], 90),
            "bsdf": {"type": "conductor"},
        },
    }


def window_room(res=RES):
    """A closed grey room lit by a window in its back wall (radiance 40, ~2% of the image) seen
    by the camera."""
    T = mi.ScalarTransform4f
    return {
        "type": "scene",
        "integrator": {"type": "path", "max_depth": 6},
        "sensor": {
            "type": "perspective",
            "fov": 70,
            "to_world": T().look_at(origin=[0, 0, 3.5], target=[0, 0, 0], up=[0, 1, 0]),
            "film": {
                "type": "hdrfilm",
                "width": res,
                "height": res,
                "rfilter": {"type": "gaussian"},
            },
            "sampler": {"type": "independent", "sample_count": 16},
        },
        "floor": {
            "type": "rectangle",
            "to_world": T().translate([0, -1, 0]).rotate([1, 0, 0], -90).scale(2),
            "bsdf": grey(0.6),
        },
        "ceiling": {
            "type": "rectangle",
            "to_world": T().translate([0, 1, 0]).rotate([1, 0, 0], 90).scale(2),
            "bsdf": grey(0.7),
        },
        "back": {
            "type": "rectangle",
            "to_world": T().translate([0, 0, -1]).scale(2),
            "bsdf": grey(0.5),
        },
        "left": {
            "type": "rectangle",
            "to_world": T().translate([-1, 0, 0]).rotate([0, 1, 0], 90).scale(2),
            "bsdf": grey(0.5),
        },
        "right": {
            "type": "rectangle",
            "to_world": T().translate([1, 0, 0]).rotate([0, 1, 0], -90).scale(2),
            "bsdf": grey(0.5),
        },
        "window": {
            "type": "rectangle",
            "to_world": T().translate([-0.3, 0.35, -0.99]).scale([0.45, 0.4, 1]),
            "emitter": {"type": "area", "radiance": {"type": "rgb", "value": [40, 40, 38]}},
        },
        "box": {
            "type": "cube",
            "to_world": T().translate([0.35, -0.65, -0.2]).scale(0.35),
            "bsdf": grey(0.4),
        },
    }
