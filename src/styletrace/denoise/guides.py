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
    # A purely specular surface (a mirror, a conductor, glass) has no diffuse albedo: Mitsuba's AOV says 0 there,
    # which tells OIDN "black, nothing to keep" and leaves the reflection's chroma noise in (cel then turns it
    # into coloured speckle: I * level / brightness(I) at a dark reflection). OIDN's guidance for perfect
    # specular surfaces is an albedo of 1: where a surface was hit (a normal) but the albedo is 0, use 1.
    hit = np.any(img[..., 3:6] != 0.0, axis=-1)
    black = hit & np.all(img[..., 0:3] <= 0.0, axis=-1)
    img[black, 0:3] = 1.0
    return tuple(np.ascontiguousarray(img[..., i:i + 3]) for i in range(0, k, 3))


def to_sensor(scene: mi.Scene):
    """The world-to-camera transform (OptiX wants the normals in the sensor's frame)."""
    return scene.sensors()[0].world_transform().inverse()


__all__ = ["first_hit", "to_sensor"]
