"""One step of the recursive `first_n_hits` parametrization between two stylized vertices: emission
at x, next-event estimation towards delta lights only (no BSDF sample can reach them), one BSDF
sample and the intersection of its ray (`bounce`; path.py walks below the last stylized vertex)."""
from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Optional

from styletrace.gate import dr, mi
from styletrace.kernel.lines import Edge
from styletrace.kernel.path import NO_HOOKS, Hooks, WalkConfig, advance, first_scattering
from styletrace.kernel.vertex import Site, depth_limit, emission, opaque_part, opaque_share


@dataclass
class Bounce:
    # emission at x plus next-event estimation towards delta lights
    L: mi.Spectrum
    weight: mi.Spectrum                  # BSDF sample weight f cos / pdf (valid where `go`)
    pi: mi.PreliminaryIntersection3f     # the next vertex
    si: mi.SurfaceInteraction3f
    ray: mi.Ray3f
    go: mi.Bool                          # lanes that took the bounce
    # ... and reached a surface (the others see the environment)
    hit: mi.Bool
    lines: Optional[Any] = None          # lines.LineState at the next vertex (where lines are on)
    tone: Optional[Any] = None           # anchors.ToneState at the next vertex (where tone is on)


def bounce(cfg: WalkConfig, sampler, site: Site, active: mi.Bool,
           hooks: Hooks = NO_HOOKS) -> Bounce:
    """One step from the stylized vertex x = `site.si` to the next, itself stylized: emission at x,
    next-event estimation to delta lights only (no BSDF sample reaches them), one BSDF sample.

    Args:
        cfg: the render's WalkConfig; with `cfg.nulls` x scatters by its opaque part only and the
            next vertex is the first scattering one past null interactions.
        sampler, site, active: the lane's random stream; the vertex x (its si, ray and depth); the
            lanes that take the step (mi.Bool).
        hooks: only `lines` (a line on the edge ends the step; weight x colour joins L) and `tone`.

    Returns:
        The Bounce: L at x, the BSDF sample's weight, the next vertex and ray, line and tone state.
    """
    scene, si, ray, depth, nulls = cfg.scene, site.si, site.ray, site.depth, cfg.nulls
    lines, tone = hooks.lines, hooks.tone
    ctx = mi.BSDFContext()
    L = emission(scene, si, active)
    go = active & (depth + 1 < depth_limit(cfg.max_depth))
    bsdf = si.bsdf(ray)
    to_light = go & mi.has_flag(bsdf.flags(), mi.BSDFFlags.Smooth)
    ds, em_weight = cfg.emitters.sample_direction(si, sampler.next_2d(), to_light)
    to_light &= ds.delta & (ds.pdf != 0.0)
    scale = opaque_part(si, bsdf, go) if nulls else 1.0
    L += dr.select(
        to_light, scale * bsdf.eval(ctx, si, si.to_local(ds.d), to_light) * em_weight, 0.0
    )
    u1 = sampler.next_1d()
    if nulls:  # x samples its opaque part alone (opaque_share): the weight is that part's f/pdf
        keep = opaque_share(si, bsdf, go)
        u1 *= keep
    bs, weight = bsdf.sample(ctx, si, u1, sampler.next_2d(), go)
    ray2 = si.spawn_ray(si.to_world(bs.wo))
    if nulls:
        weight = dr.select(
            mi.has_flag(bs.sampled_type, mi.BSDFFlags.Null) | (keep <= 0), 0.0, weight
        )
    go &= dr.max(weight) > 0
    pi2 = scene.ray_intersect_preliminary(ray2, coherent=False, active=go)
    line_state = None
    if lines is not None:  # a feature line on this edge absorbs the path (lines.py)
        seen, line_state = lines[0].edge(
            scene, sampler, lines[1], si, bs, Edge(ray2, pi2, depth + 1), go
        )
        L += dr.select(seen.fired, weight * seen.color, 0.0)
        go &= ~seen.fired
    if nulls:
        front = first_scattering(scene, sampler, pi2, ray2, go)
        pi2, ray2, weight = front.pi, front.ray, weight * front.beta
    si2 = pi2.compute_surface_interaction(ray2, ray_flags=mi.RayFlags.All, active=go)
    finite = dr.all(dr.isfinite(L)) & (~go | dr.all(dr.isfinite(weight)))  # as at the end of `walk`
    L, weight = dr.select(finite, L, 0.0), dr.select(finite, weight, 0.0)
    tone = None if tone is None else advance(tone, si, bs, depth, go)
    return Bounce(
        L=L,
        weight=weight,
        pi=pi2,
        si=si2,
        ray=ray2,
        go=go,
        hit=go & si2.is_valid(),
        lines=line_state,
        tone=tone,
    )
