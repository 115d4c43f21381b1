"""A closed room lit only by an environment through one rectangular hole (a window) in its left
wall, with an optional `portal` over the hole (tests/kernel/test_portal.py; docs/design/portals.md).

The room is x in [-2, 2], y in [0, 2.5] (floor to ceiling), z in [-2, 2]; the window is the hole
z in WINDOW_Z, y in WINDOW_Y of the wall x = -2; grey two-sided diffuse walls, a diffuse ball on
the floor, the camera in a corner looking at the window wall. Nothing outside.
"""
import numpy as np

from styletrace.gate import mi

T = mi.ScalarTransform4f
WINDOW_Z, WINDOW_Y = (-0.6, 0.6), (0.9, 1.9)


def diffuse(value: float, two_sided: bool = True) -> dict:
    bsdf = {"type": "diffuse", "reflectance": {"type": "rgb", "value": [value] * 3}}
    return {"type": "twosided", "bsdf": bsdf} if two_sided else bsdf


def rectangle(center, turns, half, bsdf) -> dict:
    """A rectangle of half sizes `half` at `center`, turned by the (axis, degrees) in `turns`."""
    t = T().translate(center)
    for axis, degrees in turns:
        t = t @ T().rotate(axis, degrees)
    return {"type": "rectangle", "to_world": t @ T().scale([half[0], half[1], 1.0]), "bsdf": bsdf}


#: the left wall's frame: its local x runs along -z, its +z normal along +x (into the room)
LEFT = [([0, 1, 0], 90)]


def portal_over_window() -> dict:
    """The `portal` that covers the window, facing into the room."""
    (z0, z1), (y0, y1) = WINDOW_Z, WINDOW_Y
    return {"type": "portal",
            "to_world": T().translate([-2.0, (y0 + y1) / 2, (z0 + z1) / 2]) @ T().rotate(*LEFT[0])
            @ T().scale([(z1 - z0) / 2, (y1 - y0) / 2, 1.0])}


def sky_map() -> mi.Bitmap:
    """A 16 x 32 environment: a blue-to-white gradient with a small bright patch (a sun of sorts)
    above the horizon."""
    v = np.linspace(0.0, 1.0, 16)[:, None, None]
    img = np.broadcast_to(0.3 + 1.5 * (1.0 - v) * np.array([0.6, 0.8, 1.0]), (16, 32, 3)).copy()
    img[2:5, 22:26] = [40.0, 35.0, 30.0]
    return mi.Bitmap(img.astype(np.float32))


def environment(kind: str) -> dict:
    """'constant' (a warm uniform sky) or 'envmap' (`sky_map`)."""
    if kind == "constant":
        return {"type": "constant", "radiance": {"type": "rgb", "value": [1.0, 0.9, 0.8]}}
    return {"type": "envmap", "bitmap": sky_map()}


def window_room(res: int, env: str = "constant", portal: bool = True,
                sampler: str = "independent") -> dict:
    """The scene dict (module docstring).

    Args:
        res: the image side. env: `environment`'s kind. portal: with the portal over the window.
        sampler: the sensor's sampler type.

    Returns:
        A Mitsuba scene dict.
    """
    wall = diffuse(0.6)
    (z0, z1), (y0, y1) = WINDOW_Z, WINDOW_Y

    def left(za, zb, ya, yb):
        return rectangle([-2.0, (ya + yb) / 2, (za + zb) / 2], LEFT, ((zb - za) / 2, (yb - ya) / 2),
                         wall)

    d = {
        "type": "scene",
        "sensor": {
            "type": "perspective", "fov": 70,
            "to_world": T().look_at(origin=[1.7, 1.4, 1.7], target=[-1.0, 0.6, -0.8], up=[0, 1, 0]),
            "sampler": {"type": sampler},
            "film": {"type": "hdrfilm", "width": res, "height": res, "rfilter": {"type": "box"}},
        },
        "floor": rectangle([0, 0, 0], [([1, 0, 0], -90)], (2, 2), diffuse(0.5)),
        "ceiling": rectangle([0, 2.5, 0], [([1, 0, 0], 90)], (2, 2), wall),
        "back": rectangle([0, 1.25, -2], [], (2, 1.25), wall),
        "front": rectangle([0, 1.25, 2], [([0, 1, 0], 180)], (2, 1.25), wall),
        "right": rectangle([2, 1.25, 0], [([0, 1, 0], -90)], (2, 1.25), wall),
        "left_below": left(-2, 2, 0, y0),
        "left_above": left(-2, 2, y1, 2.5),
        "left_back": left(-2, z0, y0, y1),
        "left_front": left(z1, 2, y0, y1),
        "ball": {"type": "sphere", "center": [0.2, 0.5, -0.3], "radius": 0.5,
                 "bsdf": diffuse(0.7, two_sided=False)},
        "sky": environment(env),
    }
    if portal:
        d["window"] = portal_over_window()
    return d
