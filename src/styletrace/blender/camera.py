"""The scene camera and render settings -> a Mitsuba sensor description.

Blender cameras look down their local -Z with +Y up and +X to the right; Mitsuba's look down +Z with
+X to the *left* of the image. So the sensor's to_world is the camera's world matrix (scale removed)
times diag(-1, 1, -1). The field of view follows Blender's sensor fit: AUTO fits the sensor width to
the larger image side. Shift moves the principal point by a fraction of the fitted side (Mitsuba's
`principal_point_offset_*` are fractions of the image's width and height). Orthographic: Mitsuba's
image spans [-1, 1] along x, scaled by to_world; Blender's ortho scale spans the fitted side. Depth
of field uses a `thinlens` with aperture radius lens / (2 f-stop), Cycles' rule (Mitsuba's thin lens
has no shift: a shift is ignored there, with a warning).
"""
from __future__ import annotations

import math

import numpy as np

from styletrace.config.choices import SAMPLER_DEFAULT

FLIP = np.diag([-1.0, 1.0, -1.0, 1.0])


def resolution(scene) -> tuple[int, int]:
    """The render's size in pixels: Blender's resolution times its percentage.

    Args:
        scene: the `bpy.types.Scene`.

    Returns:
        (width, height), each at least 1.
    """
    r = scene.render
    pct = r.resolution_percentage / 100.0
    return max(1, int(r.resolution_x * pct)), max(1, int(r.resolution_y * pct))


def _unscaled_camera(matrix) -> np.ndarray:
    m = np.array(matrix, dtype=np.float64)
    for i in range(3):
        m[:3, i] /= np.linalg.norm(m[:3, i])
    return m


def _fit_x(cam, width: int, height: int) -> bool:
    if cam.sensor_fit == "AUTO":
        return width >= height
    return cam.sensor_fit == "HORIZONTAL"


def sampler_of(scene) -> str:
    """The sampler type the scene's styletrace settings ask for (Sampling pattern).

    Args:
        scene: the `bpy.types.Scene`.

    Returns:
        A Mitsuba sampler type, `config.choices.SAMPLER_DEFAULT` where none is set.
    """
    settings = getattr(scene, "styletrace", None)
    return str(getattr(settings, "sampler", SAMPLER_DEFAULT) or SAMPLER_DEFAULT)


def sensor(scene, spp: int, obj=None, warn=print) -> dict:
    """The Mitsuba sensor (with its film and sampler) of the scene's active camera.

    Args:
        scene: the `bpy.types.Scene` (its render settings and Sampling pattern). spp: the
            sampler's sample count.
        obj: the camera object (None: the scene's active camera). warn: called with a warning
            line (a shift ignored under depth of field).

    Returns:
        The sensor description (perspective, thinlens or orthographic; rgb hdrfilm, box filter).

    Raises:
        ValueError: the scene has no active camera.
    """
    obj = obj or scene.camera
    if obj is None:
        raise ValueError("the scene has no active camera")
    cam = obj.data
    width, height = resolution(scene)
    fit_x = _fit_x(cam, width, height)
    to_world = _unscaled_camera(obj.matrix_world) @ FLIP
    film = {"type": "hdrfilm", "width": width, "height": height, "pixel_format": "rgb",
            "rfilter": {"type": "box"}}
    out = {
        "to_world": to_world,
        "near_clip": float(cam.clip_start),
        "far_clip": float(cam.clip_end),
        "film": film,
        "sampler": {"type": sampler_of(scene), "sample_count": int(spp)},
    }
    if cam.type == "ORTHO":
        half_x = cam.ortho_scale / 2.0 if fit_x else cam.ortho_scale / 2.0 * width / height
        scaled = to_world @ np.diag([half_x, half_x, 1.0, 1.0])
        shift = np.eye(4)
        # shift is in units of the ortho scale; Mitsuba's x spans 2 * half_x
        shift[0, 3] = -cam.shift_x * cam.ortho_scale / half_x
        shift[1, 3] = cam.shift_y * cam.ortho_scale / half_x
        out.update(type="orthographic", to_world=scaled @ shift)
        return out
    sensor_size = (
        cam.sensor_width if (cam.sensor_fit in ("AUTO", "HORIZONTAL")) else cam.sensor_height
    )
    fov = math.degrees(2.0 * math.atan(sensor_size / (2.0 * cam.lens)))
    out.update(fov=fov, fov_axis="x" if fit_x else "y")
    if cam.dof.use_dof and cam.dof.aperture_fstop > 0:
        focus = cam.dof.focus_distance
        if cam.dof.focus_object is not None:
            d = np.array(cam.dof.focus_object.matrix_world.translation) - np.array(
                obj.matrix_world.translation
            )
            forward = -np.array(obj.matrix_world)[:3, 2]
            focus = float(abs(d @ forward / np.linalg.norm(forward)))
        if cam.shift_x or cam.shift_y:
            warn(
                f"styletrace: camera '{cam.name}' has depth of field and a shift: the shift is "
                "ignored"
            )
        out.update(
            type="thinlens",
            aperture_radius=cam.lens / 1000.0 / (2.0 * cam.dof.aperture_fstop),
            focus_distance=max(float(focus), 1e-4),
        )
    else:
        out["type"] = "perspective"
        if cam.shift_x or cam.shift_y:
            # Blender's shift is a fraction of the fitted side; Mitsuba's offsets are fractions of
            # each side, x towards the image's right and y towards its bottom
            fitted = width if fit_x else height
            out["principal_point_offset_x"] = cam.shift_x * fitted / width
            out["principal_point_offset_y"] = -cam.shift_y * fitted / height
    return out
