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


def room_sensor(fov, origin, target, res, spp):
    """A perspective camera (y up) on a square film with a gaussian filter, Mitsuba's default."""
    return {
        "type": "perspective",
        "fov": fov,
        "to_world": mi.ScalarTransform4f().look_at(origin=origin, target=target, up=[0, 1, 0]),
        "film": {"type": "hdrfilm", "width": res, "height": res, "rfilter": {"type": "gaussian"}},
        "sampler": {"type": "independent", "sample_count": spp},
    }


def window_room(res=RES):
    """A closed grey room lit by a window in its back wall (radiance 40, ~2% of the image) seen
    by the camera."""
    T = mi.ScalarTransform4f
    return {
        "type": "scene",
        "integrator": {"type": "path", "max_depth": 6},
        "sensor": room_sensor(70, [0, 0, 3.5], [0, 0, 0], res, 16),
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


def sky_room(res=RES, spp=16):
    """A closed grey room lit only through an opening in its left wall by a small bright sky (a
    constant environment of radiance 30 outside; no lamp), seen from inside: most of the room is
    lit by paths that must find the opening after a bounce or two, which few do, and those carry
    much light: the speckled interior of a window-lit scene at a low sample count."""
    T = mi.ScalarTransform4f

    def wall(name, to_world, albedo=0.6):
        return {name: {"type": "rectangle", "to_world": to_world, "bsdf": grey(albedo)}}

    shapes = {}
    shapes.update(wall("floor", T().translate([0, -1, 0]).rotate([1, 0, 0], -90).scale(2), 0.5))
    shapes.update(wall("ceiling", T().translate([0, 1, 0]).rotate([1, 0, 0], 90).scale(2), 0.7))
    shapes.update(wall("back", T().translate([0, 0, -1]).scale(2)))
    shapes.update(wall("front", T().translate([0, 0, 3]).rotate([0, 1, 0], 180).scale(2)))
    shapes.update(wall("right", T().translate([1, 0, 0]).rotate([0, 1, 0], -90).scale(2)))
    # the left wall (x = -1, z from -1 to 3, y from -1 to 1) around an opening of z in
    # [-0.4, 0.2], y in [-0.1, 0.5]: four panels
    left = T().translate([-1, 0, 0]).rotate([0, 1, 0], 90)  # local x -> -z, local y -> y

    def panel(z0, z1, y0, y1):
        cx, cy = -(z0 + z1) / 2, (y0 + y1) / 2  # local x = -z
        return left @ T().translate([cx, cy, 0]).scale([(z1 - z0) / 2, (y1 - y0) / 2, 1])

    shapes.update(wall("left_below", panel(-1, 3, -1, -0.1)))
    shapes.update(wall("left_above", panel(-1, 3, 0.5, 1)))
    shapes.update(wall("left_back", panel(-1, -0.4, -0.1, 0.5)))
    shapes.update(wall("left_front", panel(0.2, 3, -0.1, 0.5)))
    shapes.update(wall("box", T().translate([0.3, -0.7, -0.3]).scale(0.3), 0.4))
    shapes["box"]["type"] = "cube"
    return {
        "type": "scene",
        "integrator": {"type": "path", "max_depth": 8},
        "sensor": room_sensor(75, [0.5, 0.2, 2.6], [-0.4, -0.2, -0.6], res, spp),
        "sky": {"type": "constant", "radiance": {"type": "rgb", "value": [3, 3, 3.3]}},
        **shapes,
    }
