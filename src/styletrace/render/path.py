"""The inner path tracer every stylized vertex reuses: one sample of exitant radiance.

`exitant(scene, sampler, pi, ray, active, ...)` returns one unbiased sample of
    L_o(x, wo) = L_e(x, wo) + \\int f(x, wi, wo) L_i(x, wi) cos dwi
at the vertex x that `ray` reaches (`pi`, its preliminary intersection; wo = -ray.d). Emission at x is
counted in full: in the stylized rendering equation it sits inside g. Below x the estimator is an
ordinary unidirectional path tracer with next-event estimation, multiple importance sampling (power
heuristic on solid-angle densities, as Mitsuba's `path`) and Russian roulette from `rr_depth` on. An
invalid `pi` means the ray escaped: the sample is then the environment's radiance.

Depth follows Mitsuba's convention: x is at depth `depth0` (0 for a camera ray's first hit), so
`max_depth` = 1 returns emission only, and the tree camera ray -> x -> this path has the same
longest path as Mitsuba's `path` with the same `max_depth` (-1 = unbounded).

`stop(si, depth)`, if given, marks vertices where the walk must halt because a style applies there
(per-object stylization): their radiance is g(...), not emission plus reflection, so the walk neither
adds their emission nor reflects there, and next-event estimation skips the emitters `skip_emitter(ds)`
marks (their light reaches the path through g instead). The caller gets the halted lanes back with
their throughput, intersection and ray.

The loop carries the small preliminary intersection and rebuilds the full surface interaction at the
top of each iteration, as Mitsuba's own path tracer does; the sampler is part of the loop state (a
loop drawing random numbers without it would replay the same numbers in every iteration).
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Callable, Optional

import drjit as dr
import mitsuba as mi


def mis_power(pdf_a: mi.Float, pdf_b: mi.Float) -> mi.Float:
    """Power heuristic weight of strategy a against b (0 where both densities vanish)."""
    a2 = dr.square(pdf_a)
    return dr.detach(dr.select(pdf_a > 0, a2 / dr.fma(pdf_b, pdf_b, a2), 0.0))


def depth_limit(max_depth: int) -> int:
    return 0xFFFFFFFF if max_depth < 0 else max_depth


@dataclass
class Walk:
    L: mi.Spectrum          # radiance gathered before any halt
    beta: mi.Spectrum       # throughput at the halting vertex
    pi: mi.PreliminaryIntersection3f
    ray: mi.Ray3f
    depth: mi.UInt32
    halted: mi.Bool


def exitant(scene: mi.Scene, sampler: mi.Sampler, pi: mi.PreliminaryIntersection3f, ray: mi.Ray3f,
            active: mi.Bool, max_depth: int = -1, rr_depth: int = 5, depth0=0) -> mi.Spectrum:
    """One sample of L_o at the vertex `ray` reaches (see the module docstring)."""
    return walk(scene, sampler, pi, ray, active, max_depth, rr_depth, depth0).L


def walk(scene: mi.Scene, sampler: mi.Sampler, pi: mi.PreliminaryIntersection3f, ray: mi.Ray3f,
         active: mi.Bool, max_depth: int = -1, rr_depth: int = 5, depth0=0,
         stop: Optional[Callable] = None, skip_emitter: Optional[Callable] = None) -> Walk:
    ctx = mi.BSDFContext()
    limit = depth_limit(max_depth)

    # A starting vertex counts its emission in full: the previous vertex is treated as a delta
    # scattering event, exactly like a camera ray in Mitsuba's path tracer.
    state = (
        sampler,
        mi.PreliminaryIntersection3f(pi),
        mi.Ray3f(ray),
        mi.Bool(active),
        mi.UInt32(depth0),
        mi.Spectrum(0.0),                # L
        mi.Spectrum(1.0),                # beta (throughput)
        mi.Float(1.0),                   # eta (relative IOR along the path, for roulette)
        dr.zeros(mi.Interaction3f),      # previous vertex, for the emitter density
        mi.Float(1.0),                   # BSDF density of the direction that reached the vertex
        mi.Bool(True),                   # was that direction a delta (specular) sample?
        mi.Bool(False),                  # halted at a stylized vertex
    )
    labels = ("sampler", "pi", "ray", "active", "depth", "L", "beta", "eta", "si_prev", "pdf_prev",
              "delta_prev", "halted")

    def cond(sampler, pi, ray, active, depth, L, beta, eta, si_prev, pdf_prev, delta_prev, halted):
        return active

    def body(sampler, pi, ray, active, depth, L, beta, eta, si_prev, pdf_prev, delta_prev, halted):
        si = pi.compute_surface_interaction(ray, ray_flags=mi.RayFlags.All, active=active)
        here = mi.Bool(active)
        if stop is not None:
            halt = active & si.is_valid() & stop(si, depth)
            halted |= halt
            here &= ~halt

        # Emission at si (environment where the ray escaped), MIS-weighted against the light
        # sampling done at the previous vertex.
        emitter = si.emitter(scene)
        hit_em = here & (emitter != None)  # noqa: E711  (a Dr.Jit pointer comparison)
        ds = mi.DirectionSample3f(scene, si=si, ref=si_prev)
        em_pdf = scene.pdf_emitter_direction(si_prev, ds, hit_em & ~delta_prev)
        w_em = dr.select(delta_prev, 1.0, mis_power(pdf_prev, em_pdf))
        L += beta * w_em * emitter.eval(si, hit_em)

        active_next = here & si.is_valid() & (depth + 1 < limit)
        bsdf = si.bsdf(ray)

        # Next-event estimation.
        active_em = active_next & mi.has_flag(bsdf.flags(), mi.BSDFFlags.Smooth)
        ds, em_weight = scene.sample_emitter_direction(si, sampler.next_2d(), True, active_em)
        active_em &= ds.pdf != 0.0
        if skip_emitter is not None:
            active_em &= ~skip_emitter(ds)
        wo = si.to_local(ds.d)
        # One BSDF call both evaluates the light direction and samples the continuation.
        bsdf_val, bsdf_pdf, bs, bsdf_weight = bsdf.eval_pdf_sample(ctx, si, wo, sampler.next_1d(),
                                                                   sampler.next_2d(), active_next)
        w_nee = dr.select(ds.delta, 1.0, mis_power(ds.pdf, bsdf_pdf))
        L += dr.select(active_em, beta * w_nee * bsdf_val * em_weight, 0.0)

        # Continue the path along the sampled direction (halted lanes keep their vertex).
        beta_next = beta * bsdf_weight
        eta *= dr.select(active_next, bs.eta, 1.0)
        ray_next = si.spawn_ray(si.to_world(bs.wo))
        si_prev = mi.Interaction3f(dr.detach(si, True))
        pdf_prev = bs.pdf
        delta_prev = mi.has_flag(bs.sampled_type, mi.BSDFFlags.Delta)

        # Russian roulette on the throughput, as in Mitsuba's path tracer (which counts the depth of
        # the vertex about to be reached, hence the increment first).
        depth_next = depth + 1
        beta_max = dr.max(beta_next)
        active_next &= beta_max != 0.0
        q = dr.minimum(beta_max * dr.square(eta), 0.95)
        roulette = depth_next >= rr_depth
        beta_next[roulette] *= dr.rcp(q)
        active_next &= ~roulette | (sampler.next_1d() < q)

        pi_next = scene.ray_intersect_preliminary(ray_next, coherent=False, active=active_next)
        if stop is not None:
            keep = ~here
            pi = dr.select(keep, pi, pi_next)
            ray = dr.select(keep, ray, ray_next)
            beta = dr.select(keep, beta, beta_next)
            depth = dr.select(keep, depth, depth_next)
        else:
            pi, ray, beta, depth = pi_next, ray_next, beta_next, depth_next
        return sampler, pi, ray, active_next, depth, L, beta, eta, si_prev, pdf_prev, delta_prev, halted

    out = dr.while_loop(state, cond, body, labels=labels, label="styletrace path")
    _, pi, ray, _, depth, L, beta, _, _, _, _, halted = out
    return Walk(L=L, beta=beta, pi=pi, ray=ray, depth=depth, halted=halted)
