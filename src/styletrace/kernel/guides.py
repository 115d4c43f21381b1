"""The denoiser's guides: albedo and shading normal per pixel, seen through mirrors and glass.

    g = first_hit(scene, spp=16, seed=0)   # Guides: albedo, normal, position, surface_normal
    g = first_hit(scene, 16, 0, footprint="pixel")   # each pixel the mean inside it, any filter

`albedo`: the diffuse reflectance at the first surface that is not purely specular, times the
specular weights of the mirror and glass bounces before it (`through_delta`; 1 for a surface
without diffuse reflectance); `normal`: that surface's world-space shading normal; `position`,
`surface_normal`: the first hit's own. One ray per camera sample, no path continues, so the
guides carry none of the children's noise; a pixel whose ray escapes gets 0 everywhere.
Design: docs/design/denoise_guides.md.
"""
from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from styletrace.gate import dr, mi
from styletrace.kernel.launch import LANES_PER_PASS, pass_seed, render_pass, seeded_positions

#: specular bounces followed before the chain stops (a pair of facing mirrors would go on forever);
#: a chain still specular after them keeps its specular weight as albedo
DELTA_BOUNCES = 4


class Guides(NamedTuple):
    albedo: np.ndarray
    normal: np.ndarray
    position: np.ndarray
    surface_normal: np.ndarray


def through_delta(
    scene: mi.Scene, si: mi.SurfaceInteraction3f, active: mi.Bool
) -> tuple[mi.Color3f, mi.Vector3f]:
    """(albedo, shading normal) of the first not purely specular surface along si's specular chain.

    At a purely specular surface the chain goes on along its transmission lobe where it has one,
    else its reflection, one lobe at a time (no random number: the guide stays noise-free), and the
    albedo takes that lobe's weight; DELTA_BOUNCES bounces at most.

    Args:
        scene: the scene. si: the first hits, mi.SurfaceInteraction3f. active: the lanes, mi.Bool.

    Returns:
        (albedo: mi.Color3f, normal: mi.Vector3f); a chain that escapes keeps its specular weight as
        albedo and the last surface's normal, one still specular after DELTA_BOUNCES its weight.
    """
    throughput = mi.Color3f(1.0)
    albedo = mi.Color3f(0.0)
    normal = mi.Vector3f(si.sh_frame.n)
    done = ~(active & si.is_valid())
    ctx_t = mi.BSDFContext(mi.TransportMode.Radiance, int(mi.BSDFFlags.DeltaTransmission), None)
    ctx_r = mi.BSDFContext(mi.TransportMode.Radiance, int(mi.BSDFFlags.DeltaReflection), None)
    for _ in range(DELTA_BOUNCES):
        bsdf = si.bsdf()
        flags = bsdf.flags()
        specular = mi.has_flag(flags, mi.BSDFFlags.Delta) & ~mi.has_flag(flags, mi.BSDFFlags.Smooth)
        stop = ~done & ~specular
        # a BSDF without a diffuse lobe (rough glass, a rough conductor) evaluates its glossy
        # lobe here, from 1e-5 to 36 as the view turns: no albedo; a blend's glossy part can
        # lift it above 1, which no reflectance is
        lobe = mi.has_flag(flags, mi.BSDFFlags.Diffuse)
        diffuse = dr.minimum(mi.Color3f(bsdf.eval_diffuse_reflectance(si, stop & lobe)), 1.0)
        diffuse = dr.select(~lobe | dr.all(diffuse <= 0.0), mi.Color3f(1.0), diffuse)
        albedo[stop] = throughput * diffuse
        normal[stop] = si.sh_frame.n
        done |= stop
        go = ~done
        glass = mi.has_flag(flags, mi.BSDFFlags.DeltaTransmission)
        bs_t, w_t = bsdf.sample(ctx_t, si, 0.5, mi.Point2f(0.5), go & glass)
        bs_r, w_r = bsdf.sample(ctx_r, si, 0.5, mi.Point2f(0.5), go & ~glass)
        wo = dr.select(glass, bs_t.wo, bs_r.wo)
        throughput *= mi.Color3f(dr.select(glass, w_t, w_r))
        last_normal = mi.Vector3f(si.sh_frame.n)
        si = scene.ray_intersect(si.spawn_ray(si.to_world(wo)), go)
        escaped = go & ~si.is_valid()
        albedo[escaped] = throughput
        normal[escaped] = last_normal
        done |= escaped
    albedo[~done] = throughput  # still specular after DELTA_BOUNCES
    return albedo, normal


class GuidePass(mi.SamplingIntegrator):
    """Per camera ray: the guides of the module docstring as AOVs (the image itself is 0).

    Args:
        props: Mitsuba's plugin properties (None: empty).
    """

    NAMES = ("albedo", "normal", "position", "surface_normal")

    def __init__(self, props=None):
        super().__init__(props if props is not None else mi.Properties())

    def aov_names(self):
        return [f"{name}.{c}" for name in self.NAMES for c in "XYZ"]

    def sample(self, scene, sampler, ray, medium=None, active=True):
        si = scene.ray_intersect(ray, active)
        hit = mi.Bool(active) & si.is_valid()
        albedo, normal = through_delta(scene, si, hit)
        zero = mi.Vector3f(0.0)
        parts = (albedo, normal, dr.select(hit, si.p, zero), dr.select(hit, si.sh_frame.n, zero))
        aovs = [dr.select(hit, part[i], 0.0) for part in parts for i in range(3)]
        return mi.Spectrum(0.0), mi.Bool(True), aovs


def first_hit(scene: mi.Scene, spp: int = 16, seed: int = 0, footprint: str = "film",
              lanes_per_launch: int = LANES_PER_PASS) -> Guides:
    """The guides of the film's crop window, H x W x 3 float32 each.

    Args:
        scene: the scene. spp: camera samples per pixel (callers pass the render's, so the guides
            cover the pixel as its samples do). seed: the seed (callers: the render's first pass's).
        footprint: "film" forms each pixel as the film does (its reconstruction filter: the guides
            of a rendered image, `--denoise image`); "pixel" as the mean of camera samples inside
            the pixel (a box: the guides of a per-pixel mean, `--denoise expectation`'s M). The two
            are the same for a film with a box filter.
        lanes_per_launch: the most camera rays of one kernel launch (at least one per pixel): the
            `spp` rays per pixel are split over launches of that size, so that a scene of
            thousands of camera samples per pixel takes no more memory than a pass of its render.

    Returns:
        The `Guides`: each pixel the mean over its `spp` rays, whatever the split.
    """
    w, h = (int(v) for v in scene.sensors()[0].film().crop_size())
    spp = int(spp)
    launches = max(1, math.ceil(w * h * spp / max(1, int(lanes_per_launch))))
    per = math.ceil(spp / launches)
    pixel = footprint == "pixel" and not scene.sensors()[0].film().rfilter().is_box_filter()
    parts = []
    for k, done in enumerate(range(0, spp, per)):
        n = min(per, spp - done)
        s = int(seed) if k == 0 else pass_seed(int(seed), k)
        img = _in_pixels(scene, n, s) if pixel else np.asarray(
            render_pass(scene, GuidePass(), n, s), dtype=np.float32)
        # the AOVs come last whatever the film's own channels
        parts.append((n, np.nan_to_num(img[..., -12:])))
    img = parts[0][1] if len(parts) == 1 else (
        sum(n * part for n, part in parts) / np.float32(spp)).astype(np.float32)
    return Guides(*(np.ascontiguousarray(img[..., i:i + 3]) for i in range(0, 12, 3)))


def _in_pixels(scene: mi.Scene, spp: int, seed: int) -> np.ndarray:
    """`GuidePass`'s AOVs averaged over `spp` camera rays per pixel placed inside the pixel, as a
    render with a box filter places them (the sensor's sampler, seeded alike): H x W x 12."""
    sensor = scene.sensors()[0]
    w, h = (int(v) for v in sensor.film().crop_size())
    # the seed as a kernel input: the launches of one `first_hit` share a kernel
    sampler, pos = seeded_positions(sensor, spp, dr.opaque(mi.UInt32, int(seed)))
    aperture = sampler.next_2d() if sensor.needs_aperture_sample() else mi.Point2f(0.5)
    ray, _ = sensor.sample_ray_differential(mi.Float(sensor.shutter_open()), mi.Float(0.0),
                                            mi.Point2f(pos) / mi.ScalarVector2f(w, h), aperture)
    _, _, aovs = GuidePass().sample(scene, sampler, ray)
    dr.eval(aovs)  # one kernel for all of them: each block sum would launch its own
    means = [dr.block_sum(a, spp) / spp for a in aovs]  # a pixel's lanes are next to each other
    dr.eval(means)
    return np.stack([np.asarray(m, dtype=np.float32) for m in means], -1).reshape(h, w, len(means))


def to_sensor(scene: mi.Scene):
    """The world-to-camera transform (OptiX wants the normals in the sensor's frame).

    Args:
        scene: the scene (its first sensor).

    Returns:
        The inverse of the sensor's world transform.
    """
    return scene.sensors()[0].world_transform().inverse()


__all__ = ["first_hit", "through_delta", "Guides", "GuidePass", "to_sensor"]
