"""A turntable: the camera rotated about the up axis through the point it looks at.

    target = camera_target(scene)                   # where the camera's central ray hits the scene
    mats = orbit(to_world, target, up, frames=120, degrees=360)   # each frame's sensor to_world

The target is the first hit of the ray through the image centre (Mitsuba cameras look along their
local +Z), so the turntable turns about what the picture is centred on; if that ray hits nothing,
the centre of the scene's bounding box. The axis is the camera's own up vector (its local +Y)
through the target. Frame k is turned by degrees * k / frames: a full 360 over N frames loops
without a repeated frame.
"""
from __future__ import annotations

import numpy as np

from styletrace.gate import mi
from styletrace.kernel.data_passes import to_world_of


def sensor_to_world(scene) -> np.ndarray:
    """The to_world of the scene's first sensor.

    Args:
        scene: the loaded mi.Scene.

    Returns:
        The 4x4 float64 matrix.
    """
    return to_world_of(scene.sensors()[0])


def camera_target(scene) -> np.ndarray:
    """The point a turntable turns about: the first hit of the ray through the image centre.

    Args:
        scene: the loaded mi.Scene (its first sensor looks along its local +Z).

    Returns:
        That hit (3 float64), or the centre of the scene's bounding box where the ray hits nothing.
    """
    m = sensor_to_world(scene)
    origin, forward = m[:3, 3], m[:3, 2] / np.linalg.norm(m[:3, 2])
    ray = mi.Ray3f(mi.Point3f(*map(float, origin)), mi.Vector3f(*map(float, forward)))
    si = scene.ray_intersect(ray)
    if bool(np.array(si.is_valid())[0]):
        return np.array(si.p, dtype=np.float64).reshape(3, -1)[:, 0]
    box = scene.bbox()
    return (np.array(box.min, dtype=np.float64) + np.array(box.max, dtype=np.float64)) / 2


def rotation(axis: np.ndarray, degrees: float) -> np.ndarray:
    """3x3 rotation by `degrees` about `axis` (right-handed; Rodrigues' formula).

    Args:
        axis: the axis, 3 floats (normalised here). degrees: the angle.

    Returns:
        The 3x3 float64 matrix.
    """
    a = axis / np.linalg.norm(axis)
    t = np.radians(degrees)
    k = np.array([[0, -a[2], a[1]], [a[2], 0, -a[0]], [-a[1], a[0], 0]])
    return np.eye(3) + np.sin(t) * k + (1 - np.cos(t)) * (k @ k)


def orbit(to_world: np.ndarray, target: np.ndarray, up: np.ndarray, frames: int,
          degrees: float, first: int = 0, stop: int | None = None) -> list[np.ndarray]:
    """The sensor's to_world for each frame: T(target) R(up, angle) T(-target) to_world.

    Args:
        to_world: the sensor's to_world (4x4). target: the point turned about (3).
        up: the rotation axis (3). frames: how many frames.
        degrees: the whole turn; frame k turns by degrees * k / frames (360 loops without a repeat).
        first, stop: the frames k in [first, stop) (default: 0 to frames; -1 and frames are the
            neighbours of the first and the last, for the Vector pass).

    Returns:
        One 4x4 matrix per frame k.
    """
    out = []
    for k in range(first, frames if stop is None else stop):
        about = np.eye(4)
        r = rotation(up, degrees * k / frames)
        about[:3, :3] = r
        about[:3, 3] = target - r @ target
        out.append(about @ to_world)
    return out


def turntable(scene, frames: int, degrees: float, first: int = 0,
              stop: int | None = None) -> list[np.ndarray]:
    """A scene's turntable: its camera turned about its own up vector (local +Y) through
    `camera_target`.

    Args:
        scene: the loaded mi.Scene. frames: how many frames. degrees: the whole turn.
        first, stop: the frames k in [first, stop) (`orbit`; default: all of them).

    Returns:
        One 4x4 sensor to_world per frame (`orbit`).
    """
    m = sensor_to_world(scene)
    return orbit(m, camera_target(scene), m[:3, 1], frames, degrees, first, stop)


__all__ = ["camera_target", "rotation", "orbit", "turntable", "sensor_to_world"]
