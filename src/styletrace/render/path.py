"""The inner path tracer every stylized vertex reuses: one sample of exitant radiance.

`exitant(scene, sampler, pi, ray, active, max_depth, rr_depth)` returns one unbiased sample of
    L_o(x, wo) = L_e(x, wo) + \\int f(x, wi, wo) L_i(x, wi) cos dwi
at the vertex x that `ray` reaches (`pi`, its preliminary intersection; wo = -ray.d). Emission at x is counted in full: in the
stylized rendering equation it sits inside g. Below x the estimator is an ordinary unidirectional
path tracer with next-event estimation, multiple importance sampling (power heuristic on solid-angle
densities, as Mitsuba's `path`) and Russian roulette after `rr_depth` bounces. An invalid `pi` means
the ray escaped: the sample is then the environment's radiance.

The loop carries the small preliminary intersection and rebuilds the full surface interaction at the
top of each iteration, as Mitsuba's own path tracer does: a full SurfaceInteraction3f in the loop
state costs more in register pressure than recomputing it.

Depth follows Mitsuba's convention: x is at depth 0, so `max_depth` = 1 returns emission only and
a tree of (camera ray -> x -> this path) has the same maximum length as Mitsuba's `path` with the
same `max_depth` (-1 = unbounded).

The sampler is part of the loop state: a loop that draws random numbers without it would replay the
same numbers in every iteration.
"""
from __future__ import annotations

import drjit as dr
import mitsuba as mi


def mis_power(pdf_a: mi.Float, pdf_b: mi.Float) -> mi.Float:
    """Power heuristic weight of strategy a against b (0 where both densities vanish)."""
    a2 = dr.square(pdf_a)
    return dr.detach(dr.select(pdf_a > 0, a2 / dr.fma(pdf_b, pdf_b, a2), 0.0))


def max_depth_bound(max_depth: int) -> int:
    return 0xFFFFFFFF if max_depth < 0 else max_depth


def exitant(scene: mi.Scene, sampler: mi.Sampler, pi: mi.PreliminaryIntersection3f, ray: mi.Ray3f,
            active: mi.Bool, max_depth: int = -1, rr_depth: int = 5) -> mi.Spectrum:
    ctx = mi.BSDFContext()
    limit = max_depth_bound(max_depth)

    # A starting vertex counts its emission in full: the previous vertex is treated as a delta
    # scattering event, exactly like a camera ray in Mitsuba's path tracer.
    state = (
        sampler,
        mi.PreliminaryIntersection3f(pi),
        mi.Ray3f(ray),
        mi.Bool(active),
        mi.UInt32(0),                    # depth of si
        mi.Spectrum(0.0),                # L
        mi.Spectrum(1.0),                # beta (throughput)
        mi.Float(1.0),                   # eta (relative IOR along the path, for roulette)
        dr.zeros(mi.Interaction3f),      # previous vertex, for the emitter density
        mi.Float(1.0),                   # BSDF density of the direction that reached si
        mi.Bool(True),                   # was that direction a delta (specular) sample?
    )

    def cond(sampler, pi, ray, active, depth, L, beta, eta, si_prev, pdf_prev, delta_prev):
        return active

    def body(sampler, pi, ray, active, depth, L, beta, eta, si_prev, pdf_prev, delta_prev):
        si = pi.compute_surface_interaction(ray, ray_flags=mi.RayFlags.All, active=active)
        # Emission at si (environment where the ray escaped), MIS-weighted against the light
        # sampling done at the previous vertex.
        emitter = si.emitter(scene)
        hit_em = active & (emitter != None)  # noqa: E711  (a Dr.Jit pointer comparison)
        ds = mi.DirectionSample3f(scene, si=si, ref=si_prev)
        em_pdf = scene.pdf_emitter_direction(si_prev, ds, hit_em & ~delta_prev)
        w_em = dr.select(delta_prev, 1.0, mis_power(pdf_prev, em_pdf))
        L += beta * w_em * emitter.eval(si, hit_em)

        active_next = active & si.is_valid() & (depth + 1 < limit)
        bsdf = si.bsdf(ray)

        # Next-event estimation.
        active_em = active_next & mi.has_flag(bsdf.flags(), mi.BSDFFlags.Smooth)
        ds, em_weight = scene.sample_emitter_direction(si, sampler.next_2d(), True, active_em)
        active_em &= ds.pdf != 0.0
        wo = si.to_local(ds.d)
        # One BSDF call both evaluates the light direction and samples the continuation.
        bsdf_val, bsdf_pdf, bs, bsdf_weight = bsdf.eval_pdf_sample(ctx, si, wo, sampler.next_1d(),
                                                                   sampler.next_2d(), active_next)
        w_nee = dr.select(ds.delta, 1.0, mis_power(ds.pdf, bsdf_pdf))
        L += dr.select(active_em, beta * w_nee * bsdf_val * em_weight, 0.0)

        # Continue the path along the sampled direction.
        beta *= bsdf_weight
        eta *= bs.eta
        ray = si.spawn_ray(si.to_world(bs.wo))
        si_prev = mi.Interaction3f(dr.detach(si, True))
        pdf_prev = bs.pdf
        delta_prev = mi.has_flag(bs.sampled_type, mi.BSDFFlags.Delta)

        # Russian roulette on the throughput, as in Mitsuba's path tracer (which counts the depth of
        # the vertex about to be reached, hence the increment first).
        depth += 1
        beta_max = dr.max(beta)
        active_next &= beta_max != 0.0
        q = dr.minimum(beta_max * dr.square(eta), 0.95)
        roulette = depth >= rr_depth
        beta[roulette] *= dr.rcp(q)
        active_next &= ~roulette | (sampler.next_1d() < q)

        pi = scene.ray_intersect_preliminary(ray, coherent=False, active=active_next)
        return sampler, pi, ray, active_next, depth, L, beta, eta, si_prev, pdf_prev, delta_prev

    out = dr.while_loop(state, cond, body, labels=("sampler", "pi", "ray", "active", "depth", "L", "beta", "eta",
                                                    "si_prev", "pdf_prev", "delta_prev"),
                        label="styletrace inner path")
    return out[5]
