"""One batch of a reuse pass: camera rays, first hits, their children drawn and stored, pooled,
then g.

Every camera sample i traces its ray to the first hit v_i and draws m children there (m = its style
slot's inner_samples, reuse_children.py); the pool of v_i (reuse_pool.py; its world-space second
level with reuse_deep=world, reuse_world.py; the refinement round of an adaptive count,
reuse_refine.py) gives L(v) = g(L_e(v) + direct + indirect). Lanes whose BSDF has a delta or null
component, closed-form styles and escaped rays use their own children only (the ordinary estimate,
with MIS); a pool of v alone is the ordinary estimate too.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from styletrace.gate import dr, mi
from styletrace.kernel.lane_sampler import LaneSampler
from styletrace.kernel.path import past_area_emitters
from styletrace.kernel.reuse_children import Children, Parents, Slab, Span, draw
from styletrace.kernel.reuse_pool import Frame, Grid, Pools, pooled
from styletrace.kernel.reuse_refine import Round, refine_pools
from styletrace.kernel.reuse_scope import (
    children_per_lane,
    first_round,
    refined,
    slots,
    styled_value,
)
from styletrace.kernel.reuse_world import level1
from styletrace.kernel.vertex import emission, environment
from styletrace.styles.base import Vertex


@dataclass(frozen=True)
class Samples:
    """A batch's camera samples: their values (g of the pooled estimate, times the ray weight),
    which are valid, their film positions and wavelengths."""
    value: mi.Spectrum
    valid: mi.Bool
    pos: mi.Point2f
    wavelengths: object


def camera_rays(sensor, sampler, frame: Frame, spp_total: int):
    """Camera rays as Mitsuba's SamplingIntegrator::render makes them: lane = pixel * spp +
    sample index, over the film's crop (border included).

    Args:
        sensor, sampler: the scene's sensor and the batch's seeded sampler.
        frame: the batch's pixels and camera samples per pixel.
        spp_total: the pass's camera samples per pixel (the ray differentials are scaled by 1/sqrt
            of it).

    Returns:
        (mi.RayDifferential3f, its weight mi.Spectrum, film position mi.Vector2f) per lane.
    """
    film = sensor.film()
    width, spp = frame.width, frame.spp
    N = width * frame.height * spp
    idx = dr.arange(mi.UInt32, N) // spp
    y = idx // width
    pos = mi.Vector2i(mi.Int32(idx - y * width), mi.Int32(y))
    if film.sample_border():
        pos -= mi.Vector2i(film.rfilter().border_size())
    pos += mi.Vector2i(film.crop_offset())
    pos_f = mi.Vector2f(pos) + sampler.next_2d()
    scale = dr.rcp(mi.ScalarVector2f(film.crop_size()))
    adjusted = dr.fma(pos_f, scale, -mi.ScalarVector2f(film.crop_offset()) * scale)
    aperture = sampler.next_2d() if sensor.needs_aperture_sample() else mi.Point2f(0.5)
    time = mi.Float(sensor.shutter_open())
    if sensor.shutter_open_time() > 0:
        time += sampler.next_1d() * sensor.shutter_open_time()
    ray, weight = sensor.sample_ray_differential(time, 0.0, adjusted, aperture)
    if ray.has_differentials:
        ray.scale_differential(dr.rsqrt(spp_total))
    return ray, weight, pos_f


def batch(scope, sensor, frame: Frame, seed: int, spp_total: int) -> Samples:
    """One batch of a reuse pass: camera rays, first hits, children, pools, then g.

    Args:
        scope: the render's Scope (its `keep`, if any, receives this batch's pools).
        sensor: the scene's sensor.
        frame: the batch's pixels and its camera samples per pixel (frame.spp of the pass's
            spp_total).
        seed: the batch's sampler seed.
        spp_total: the pass's camera samples per pixel.

    Returns:
        The batch's `Samples`.
    """
    s, scene, keep, targets = scope.settings, scope.scene, scope.keep, scope.targets
    width, height, spp = frame.width, frame.height, frame.spp
    N = width * height * spp
    sampler = sensor.sampler().clone()
    sampler.set_sample_count(spp)
    sampler.set_samples_per_wavefront(spp)
    sampler.seed(seed, N)
    ray, ray_weight, pos = camera_rays(sensor, sampler, frame, spp_total)
    ray = mi.Ray3f(ray)
    origin = mi.Point3f(ray.o)
    lanes = LaneSampler.seeded_from(sampler, N)
    pi = scene.ray_intersect_preliminary(ray, coherent=True)
    if s.hide_emitters:
        ray, pi = past_area_emitters(scene, ray, pi, mi.Bool(True))
    valid = pi.is_valid() | (scene.environment() is not None and not s.hide_emitters)
    si = pi.compute_surface_interaction(ray, ray_flags=mi.RayFlags.All)
    hit = si.is_valid()
    bsdf = si.bsdf(ray)

    # which target (style slot) each lane belongs to, its children count m, and whether it may pool
    lane_slots = slots(scope, si, hit, bsdf, 0)
    target, m, pool = lane_slots.target, lane_slots.m, lane_slots.pool
    M = children_per_lane(targets)
    again = refined(targets)

    # the children, stored per lane: child j of lane i at i * M + j
    slab = Slab(Children(N * M), M)
    kids = slab.kids
    base = dr.select(
        hit, emission(scene, si, hit), 0.0 if s.hide_emitters else environment(scene, si, ~hit)
    )
    lane = dr.arange(mi.UInt32, N)
    if s.reuse_deep == "world":
        own = level1(scope, lanes, Parents(si, bsdf, hit & (m > 0), None), m, slab)
    else:
        own = draw(scope, lanes, Parents(si, bsdf, hit & (m > 0), pool),
                   Span(mi.UInt32(0), m, first_round(targets), slab, lane))
    W = (2 * s.reuse_radius + 1) ** 2 - 1
    K = min(s.reuse_k, W)  # settings.parse keeps K <= MAX_REUSE_K
    start = mi.UInt32(dr.minimum(lanes.next_1d() * W, W - 1)) if K < W else dr.zeros(mi.UInt32, N)
    depth = dr.norm(si.p - origin)
    # the refinement round seeds its children from the lanes' generators: evaluated with the first
    # round's children, or reading them would trace the first round again
    dr.eval(
        kids,
        own,
        base,
        si,
        target,
        m,
        pool,
        depth,
        start,
        bsdf,
        valid,
        ray_weight,
        pos,
        lanes if again else (),
    )

    grid = Grid(frame, s.reuse_radius, K, start)
    mask = grid.accepted(target, bsdf, pool, mi.Vector3f(si.sh_frame.n), depth)
    dr.eval(mask)
    if keep is not None:
        keep.update(
            mask=np.asarray(mask, dtype=np.uint64),
            start=np.asarray(start, dtype=np.int64),
            spp=spp,
            width=width,
            height=height,
            K=K,
            radius=s.reuse_radius,
            target=np.asarray(target),
        )
    v = Vertex(
        p=si.p,
        n=mi.Vector3f(si.sh_frame.n),
        wo=-ray.d,
        view=mi.Vector3f(scope.view),
        depth=mi.UInt32(0),
    )
    count = m
    pools = Pools(grid, mask, si, bsdf, m)
    if again:
        mean, s1, s2, C = pooled(pools, slab, first_round(targets), scope.weights, moments=True)
        first = Round(base, mean, s1, s2, C)
        mean, count = refine_pools(scope, lanes, pools, lane_slots, slab, v, first)
    else:
        mean = pooled(pools, slab, first_round(targets), scope.weights)
    mean = dr.select(pool, mean, own / mi.Float(dr.maximum(m, 1)))
    x = base + mean
    # what g sees, the children each lane pooled as its own, and those it stored
    if keep is not None:
        stored = np.asarray(dr.squared_norm(kids.directions()) > 0).reshape(N, M).sum(axis=1)
        keep.update(x=np.asarray(x), children=np.asarray(count), stored=stored)
    value = styled_value(scope, target, x, v, base)
    return Samples(value * ray_weight, valid, pos, ray.wavelengths)
