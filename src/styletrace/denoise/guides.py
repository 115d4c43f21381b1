"""The denoiser's guides: first-hit albedo and shading normal per pixel, from Mitsuba's `aov` integrator.

    albedo, normal = first_hit(scene, spp=16, seed=0)      # H x W x 3 float32 each

Parameters: `spp` camera samples per pixel (default 16; the render's own count is passed by the callers,
so the guides cover the pixel as its camera samples do), `seed` (default 0: the render's first pass seed).
The albedo is the BSDF's `albedo` AOV (its directional albedo, textures included); the normal is the world-space
shading normal. Both are free of the children's noise: one ray per camera sample, no path continues.
Pixels where the camera ray escapes get 0 in both (OIDN's convention for "nothing there").
"""
from __future__ import annotations

import numpy as np

from ..jit import backend

backend()

import mitsuba as mi  # noqa: E402


def first_hit(scene: mi.Scene, spp: int = 16, seed: int = 0) -> tuple[np.ndarray, np.ndarray]:
    aov = mi.load_dict({"type": "aov", "aovs": "albedo:albedo,nn:sh_normal"})
    img = np.asarray(mi.render(scene, integrator=aov, spp=int(spp), seed=int(seed)), dtype=np.float32)
    img = np.nan_to_num(img[..., -6:])  # the AOVs come last whatever the film's own channels
    return np.ascontiguousarray(img[..., :3]), np.ascontiguousarray(img[..., 3:6])


def to_sensor(scene: mi.Scene):
    """The world-to-camera transform (OptiX wants the normals in the sensor's frame)."""
    return scene.sensors()[0].world_transform().inverse()


__all__ = ["first_hit", "to_sensor"]
