"""The denoiser's guides: first-hit albedo and shading normal per pixel, from Mitsuba's `aov` integrator.

    albedo, normal = first_hit(scene, spp=16, seed=0)      # H x W x 3 float32 each
    albedo, normal, position = first_hit(scene, spp, seed, position=True)

Parameters: `spp` camera samples per pixel (default 16; the render's own count is passed by the callers,
so the guides cover the pixel as its camera samples do), `seed` (default 0: the render's first pass seed).
The albedo is the BSDF's `albedo` AOV (its directional albedo, textures included); the normal is the world-space
shading normal. Both are free of the children's noise: one ray per camera sample, no path continues.
Pixels where the camera ray escapes get 0 in both (OIDN's convention for "nothing there"). With
`position=True` the pixel's mean first-hit position comes too (the sub-pixel interpolation of
`denoise.expectation` compares it with a camera sample's own vertex).
"""
from __future__ import annotations

import numpy as np

from ..jit import backend

backend()

import mitsuba as mi  # noqa: E402


def first_hit(scene: mi.Scene, spp: int = 16, seed: int = 0, position: bool = False) -> tuple[np.ndarray, ...]:
    aovs = "albedo:albedo,nn:sh_normal" + (",pos:position" if position else "")
    k = 9 if position else 6
    aov = mi.load_dict({"type": "aov", "aovs": aovs})
    img = np.asarray(mi.render(scene, integrator=aov, spp=int(spp), seed=int(seed)), dtype=np.float32)
    img = np.nan_to_num(img[..., -k:])  # the AOVs come last whatever the film's own channels
    return tuple(np.ascontiguousarray(img[..., i:i + 3]) for i in range(0, k, 3))


def to_sensor(scene: mi.Scene):
    """The world-to-camera transform (OptiX wants the normals in the sensor's frame)."""
    return scene.sensors()[0].world_transform().inverse()


__all__ = ["first_hit", "to_sensor"]
