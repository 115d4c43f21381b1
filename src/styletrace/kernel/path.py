"""The inner path tracer every stylized vertex reuses: one sample of exitant radiance.

    cfg = WalkConfig(scene, emitters, max_depth, rr_depth, nulls, media)   # once per render
    w = walk(cfg, sampler, Start(pi, ray, depth), active, Hooks(stop=...))  # a Walk

`exitant` samples L_o(x, wo) = L_e(x, wo) + \\int f L_i cos dwi at the vertex x that `start.ray`
reaches (emission in full: it sits inside g), the environment where the ray escaped. Below x:
next-event estimation (emitters by `EmitterSampler`), power-heuristic MIS and Russian roulette, as
Mitsuba's `path`, with its depth convention (x at `start.depth`; max_depth -1: unbounded). `Hooks`
halt the walk on styled vertices, skip emitters, detect lines and carry tone; volume.py's walk
serves scenes with media. Design: docs/design/path_kernel.md.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Callable, Optional

from styletrace.gate import dr, mi
from styletrace.kernel.anchors import MAX_BITS, ToneState, combine, shape_id
from styletrace.kernel.emitter_sampler import EmitterSampler
from styletrace.kernel.lines import Edge
from styletrace.kernel.vertex import depth_limit, mis_power, null_split, opaque_part, opaque_share


@dataclass(frozen=True)
class WalkConfig:
    """What every walk of one render shares (built once per render: render_context.py).

    scene: the scene traced; emitters: its EmitterSampler; max_depth, rr_depth: Mitsuba's (-1: no
    limit); nulls: the scene has null-scattering surfaces; media: it has participating media (the
    walks are volume.py's). The switches are Python values: a scene without such surfaces or media
    traces the plain loop.
    """
    scene: mi.Scene
    emitters: EmitterSampler
    max_depth: int = -1
    rr_depth: int = 5
    nulls: bool = False
    media: bool = False


@dataclass(frozen=True)
class Hooks:
    """What a caller adds to one walk (module docstring); None: that code is not traced.

    stop: stop(si, depth) -> Bool, lanes that halt at si; skip_emitter: skip_emitter(ds) -> Bool,
    lights that next-event estimation leaves out; lines: (lines.Lines, lines.LineState at the start
    vertex); tone: anchors.ToneState at the start vertex. Volume walks only: halt_in_medium:
    halt_in_medium(depth) -> Bool, lanes that halt at a real scattering collision in a medium
    (the Walk's `collision`). groups: light_groups.GroupTable, the radiance also split by the
    group of the emitter each contribution ends on (the Walk's `Lg`; surface walks only).
    """
    stop: Optional[Callable] = None
    skip_emitter: Optional[Callable] = None
    lines: Optional[tuple] = None
    tone: Optional[Any] = None
    halt_in_medium: Optional[Callable] = None
    groups: Optional[Any] = None


NO_HOOKS = Hooks()


@dataclass
class Start:
    """Where a walk starts and how its start vertex scatters.

    pi, ray: the start vertex's preliminary intersection and the ray that reaches it; depth: its
    depth. opaque: it scatters by its opaque part only (`opaque_part`, where the scene has null
    surfaces). came_from: (interaction, BSDF pdf, delta) of a vertex the caller sampled `ray` from:
    emission at the start vertex is then MIS-weighted against that vertex's next-event estimation
    (surface walks). Volume walks only: medium, the medium `ray` travels in; flight, sample it along
    `ray` before `pi`; delta, the start vertex samples delta lights only; hide, no emission before
    the first scattering.
    """
    pi: mi.PreliminaryIntersection3f
    ray: mi.Ray3f
    depth: Any = 0
    opaque: bool = False
    came_from: Optional[tuple] = None
    medium: Any = None
    flight: bool = False
    delta: bool = False
    hide: bool = False
    collision: Optional[Any] = None


@dataclass
class Front:
    """The first scattering vertex along a ray, past surfaces it went straight through."""
    pi: mi.PreliminaryIntersection3f
    ray: mi.Ray3f
    beta: mi.Spectrum       # weight of the passes (1 where none)


@dataclass
class FrontState:
    sampler: Any
    pi: mi.PreliminaryIntersection3f
    ray: mi.Ray3f
    beta: mi.Spectrum
    active: mi.Bool


def first_scattering(scene: mi.Scene, sampler, pi: mi.PreliminaryIntersection3f, ray: mi.Ray3f,
                     active: mi.Bool) -> Front:
    """Follow `ray` through null interactions (masks, `null` BSDFs) to the first vertex that
    scatters: a mask passes the ray with probability T (its null transmission), else it is an
    opaque surface there and the lane's weight is (1 - T)/(1 - p) (1 for grey T). Null
    interactions add no depth. Emitters on see-through surfaces must be refused beforehand
    (scene_graph.py; docs/design/path_kernel.md).

    Args:
        scene, sampler: the scene and the lane's random stream.
        pi, ray: the ray's first intersection (preliminary) and the ray. active: lanes to follow.

    Returns:
        The Front: the scattering vertex, the ray that reaches it, the passes' weight beta.
    """
    state = FrontState(sampler=sampler, pi=mi.PreliminaryIntersection3f(pi), ray=mi.Ray3f(ray),
                       beta=mi.Spectrum(1.0), active=mi.Bool(active))

    def body(s: FrontState):
        si = s.pi.compute_surface_interaction(s.ray, ray_flags=mi.RayFlags.All, active=s.active)
        bsdf = si.bsdf(s.ray)
        nullish = s.active & si.is_valid() & mi.has_flag(bsdf.flags(), mi.BSDFFlags.Null)
        passes, w_pass, w_stay = null_split(si, bsdf, s.sampler.next_1d(nullish), nullish)
        s.beta *= dr.select(passes, w_pass, dr.select(nullish, w_stay, 1.0))
        ray_next = si.spawn_ray(s.ray.d)
        pi_next = scene.ray_intersect_preliminary(ray_next, coherent=False, active=passes)
        s.pi = dr.select(passes, pi_next, s.pi)
        s.ray = dr.select(passes, ray_next, s.ray)
        s.active = passes & (dr.max(s.beta) > 0)
        return (s,)

    (out,) = dr.while_loop((state,), lambda s: s.active, body, label="styletrace null passes")
    return Front(pi=out.pi, ray=out.ray, beta=out.beta)


@dataclass
class PathState:
    """What the path loop carries from one vertex to the next (a Dr.Jit PyTree: the loop state)."""

    # LaneSampler (or a Mitsuba sampler): must travel in the state
    sampler: Any
    pi: mi.PreliminaryIntersection3f         # the vertex about to be shaded
    ray: mi.Ray3f                            # the ray that reached it
    active: mi.Bool
    depth: mi.UInt32
    L: mi.Spectrum                           # radiance gathered so far
    beta: mi.Spectrum                        # throughput
    eta: mi.Float                            # relative IOR along the path, for roulette
    si_prev: mi.Interaction3f                # previous vertex, for the emitter density
    pdf_prev: mi.Float                       # BSDF density of the direction that reached the vertex
    delta_prev: mi.Bool                      # was that direction a delta (specular) sample?
    halted: mi.Bool                          # halted at a stylized vertex
    # at the starting vertex (only where `opaque_start` needs it)
    first: Optional[mi.Bool]
    lines: Optional[Any] = None              # lines.LineState where feature lines are on (lines.py)
    # anchors.ToneState where a style reads image coordinates
    tone: Optional[Any] = None
    # L split by light group (one mi.Spectrum per group) where the walk has Hooks.groups
    Lg: Optional[list] = None


@dataclass
class Walk:
    L: mi.Spectrum          # radiance gathered before any halt
    beta: mi.Spectrum       # throughput at the halting vertex
    pi: mi.PreliminaryIntersection3f
    ray: mi.Ray3f
    depth: mi.UInt32
    halted: mi.Bool
    lines: Optional[Any] = None     # lines.LineState at the halting vertex (where lines are on)
    # MediumPtr: the medium each lane stands in (volume.py's walk only)
    medium: Any = None
    tone: Optional[Any] = None      # anchors.ToneState at the halting vertex (where tone is on)
    # volume.Collision: lanes halted in a medium rather than at `pi` (Hooks.halt_in_medium only)
    collision: Optional[Any] = None
    # L split by light group, in the groups' order (Hooks.groups only)
    Lg: Optional[list] = None


def exitant(cfg: WalkConfig, sampler, start: Start, active: mi.Bool) -> mi.Spectrum:
    """One sample of L_o at the vertex `start.ray` reaches (see the module docstring).

    Args:
        cfg: the render's WalkConfig. sampler: the lane's random stream.
        start: where the walk starts. active: the lanes that walk (mi.Bool).

    Returns:
        mi.Spectrum.
    """
    return walk(cfg, sampler, start, active).L


def walk(cfg: WalkConfig, sampler, start: Start, active: mi.Bool, hooks: Hooks = NO_HOOKS) -> Walk:
    """The path loop (module docstring) from `start`: returns the Walk (radiance, and throughput,
    vertex, depth, line and tone state where it halted); non-finite samples are dropped.

    With `cfg.nulls` halting lanes pass their null part first (`null_split`); with `start.opaque`
    the start vertex scatters by its opaque part only.

    Args:
        cfg, sampler: the render's WalkConfig and the lane's random stream.
        start, active: where the walk starts, and the lanes that walk (mi.Bool).
        hooks: stop, skip_emitter, lines (a line on an edge absorbs the path: throughput x line
            colour) and tone (advanced at every scattering).
    """
    scene, emitters, nulls = cfg.scene, cfg.emitters, cfg.nulls
    stop, skip_emitter, lines, tone = hooks.stop, hooks.skip_emitter, hooks.lines, hooks.tone
    groups = hooks.groups
    opaque_start, came_from, rr_depth = start.opaque, start.came_from, cfg.rr_depth
    ctx = mi.BSDFContext()
    limit = depth_limit(cfg.max_depth)

    # A starting vertex counts its emission in full: the previous vertex is treated as a delta
    # scattering event, exactly like a camera ray in Mitsuba's path tracer.
    si_prev, pdf_prev, delta_prev = (
        (dr.zeros(mi.Interaction3f), mi.Float(1.0), mi.Bool(True))
        if came_from is None
        else (mi.Interaction3f(came_from[0]), mi.Float(came_from[1]), mi.Bool(came_from[2]))
    )
    state = PathState(
        sampler=sampler,
        pi=mi.PreliminaryIntersection3f(start.pi),
        ray=mi.Ray3f(start.ray),
        active=mi.Bool(active),
        depth=mi.UInt32(start.depth),
        L=mi.Spectrum(0.0),
        beta=mi.Spectrum(1.0),
        eta=mi.Float(1.0),
        si_prev=si_prev,
        pdf_prev=pdf_prev,
        delta_prev=delta_prev,
        halted=mi.Bool(False),
        first=mi.Bool(True) if nulls and opaque_start else None,
        lines=None if lines is None else lines[1],
        tone=tone,
        Lg=None if groups is None else groups.zeros(),
    )

    def body(s: PathState):
        si = s.pi.compute_surface_interaction(s.ray, ray_flags=mi.RayFlags.All, active=s.active)
        bsdf = si.bsdf(s.ray)
        here, passes, w_pass = halt_at(s, si, bsdf, s.active, stop, nulls)
        emitted = mis_emission(scene, emitters, s, si, here)
        s.L += emitted
        if groups is not None:  # the light of the emitter it ends on: that emitter's group
            s.Lg = groups.split(s.Lg, si.emitter(scene), emitted, here)

        active_next = here & si.is_valid() & (s.depth + 1 < limit)

        # Next-event estimation.
        active_em = active_next & mi.has_flag(bsdf.flags(), mi.BSDFFlags.Smooth)
        ds, em_weight = emitters.sample_direction(si, s.sampler.next_2d(), active_em)
        active_em &= ds.pdf != 0.0
        if skip_emitter is not None:
            active_em &= ~skip_emitter(ds)
        wo = si.to_local(ds.d)
        u1 = s.sampler.next_1d()
        # the stylized starting vertex samples its opaque part alone (opaque_share)
        if nulls and opaque_start:
            keep = dr.select(s.first, opaque_share(si, bsdf, active_next & s.first), 1.0)
            u1 = dr.select(s.first, u1 * keep, u1)
        # One BSDF call both evaluates the light direction and samples the continuation.
        bsdf_val, bsdf_pdf, bs, bsdf_weight = bsdf.eval_pdf_sample(
            ctx, si, wo, u1, s.sampler.next_2d(), active_next
        )
        scale = mi.Spectrum(1.0)
        if nulls and opaque_start:
            # the opaque part's f and pdf: the BSDF's own are (1 - T) and (1 - p) times theirs,
            # while the weight f/pdf of a sample drawn from the opaque part alone is already
            # that part's
            scale = dr.select(s.first, opaque_part(si, bsdf, active_next & s.first), 1.0)
            ok = keep > 0
            bsdf_pdf = dr.select(ok, bsdf_pdf / dr.select(ok, keep, 1.0), 0.0)
            bs.pdf = dr.select(ok, bs.pdf / dr.select(ok, keep, 1.0), 0.0)
            bsdf_weight[~ok | (s.first & mi.has_flag(bs.sampled_type, mi.BSDFFlags.Null))] = 0.0
        w_nee = dr.select(ds.delta, 1.0, mis_power(ds.pdf, bsdf_pdf))
        if nulls and stop is not None:
            active_em &= ~passes
        direct = dr.select(active_em, s.beta * scale * w_nee * bsdf_val * em_weight, 0.0)
        s.L += direct
        if groups is not None:
            s.Lg = groups.split(s.Lg, ds.emitter, direct, active_em)

        # Continue the path along the sampled direction (halted lanes keep their vertex).
        beta_next = s.beta * bsdf_weight
        s.eta *= dr.select(active_next & ~passes, bs.eta, 1.0)
        ray_next = si.spawn_ray(si.to_world(bs.wo))
        s.si_prev = mi.Interaction3f(dr.detach(si, True))
        s.pdf_prev = bs.pdf
        s.delta_prev = mi.has_flag(bs.sampled_type, mi.BSDFFlags.Delta)
        # straight on through the null part, like a sampled null component
        if nulls and stop is not None:
            beta_next = dr.select(passes, s.beta * w_pass, beta_next)
            ray_next = dr.select(passes, si.spawn_ray(s.ray.d), ray_next)
            s.delta_prev |= passes
        if nulls and opaque_start:
            s.first = mi.Bool(False)
        # the prefix the next vertex's image coordinate is searched with (anchors.py)
        if tone is not None:
            s.tone = advance(s.tone, si, bs, s.depth, active_next & ~passes)

        # Russian roulette on the throughput, as in Mitsuba's path tracer (which counts the depth of
        # the vertex about to be reached, hence the increment first).
        depth_next = s.depth + 1
        beta_max = dr.max(beta_next)
        active_next &= beta_max != 0.0
        q = dr.minimum(beta_max * dr.square(s.eta), 0.95)
        roulette = depth_next >= rr_depth
        beta_next[roulette] *= dr.rcp(q)
        active_next &= ~roulette | (s.sampler.next_1d() < q)

        pi_next = scene.ray_intersect_preliminary(ray_next, coherent=False, active=active_next)
        if lines is not None:  # a feature line on the new edge absorbs the path (lines.py)
            seen, s.lines = lines[0].edge(
                scene, s.sampler, s.lines, si, bs, Edge(ray_next, pi_next, depth_next), active_next
            )
            s.L += dr.select(seen.fired, beta_next * seen.color, 0.0)
            active_next &= ~seen.fired
        if stop is not None:  # halted lanes keep their vertex
            keep = ~here
            pi_next = dr.select(keep, s.pi, pi_next)
            ray_next = dr.select(keep, s.ray, ray_next)
            beta_next = dr.select(keep, s.beta, beta_next)
            depth_next = dr.select(keep, s.depth, depth_next)
        s.pi, s.ray, s.beta, s.depth = pi_next, ray_next, beta_next, depth_next
        s.active = active_next
        return (s,)

    (out,) = dr.while_loop((state,), lambda s: s.active, body, label="styletrace path")
    # A sample that is not finite is dropped here, before it reaches a style's estimator or the
    # film: one NaN poisons its pixel for good (every pass is averaged in) and g of a mean
    # containing it. Such samples come from measure-zero events (degenerate geometry, 0 * inf), so
    # dropping them costs a bias no larger than their probability times their true value; the causes
    # known are fixed at their source (`mis_power`), this keeps an unknown one from destroying
    # a render.
    extra = {} if groups is None else {"Lg": out.Lg}
    return finished(out, lines=out.lines, tone=out.tone, **extra)


def finished(out, **extra) -> Walk:
    """The Walk of a finished loop state `out`, its sample dropped where it is not finite (see
    `walk`). The throughput counts only where the walk halted (lanes that Russian roulette ended may
    hold inf * 0).

    Args:
        out: the loop's final state (PathState or volume.VolumeState).
        extra: further Walk fields (lines, tone, medium).

    Returns:
        Walk.
    """
    finite = dr.all(dr.isfinite(out.L)) & (~out.halted | dr.all(dr.isfinite(out.beta)))
    if extra.get("Lg") is not None:  # dropped with L, whose parts they are
        extra["Lg"] = [dr.select(finite, L, 0.0) for L in extra["Lg"]]
    return Walk(
        L=dr.select(finite, out.L, 0.0),
        beta=dr.select(finite, out.beta, 0.0),
        pi=out.pi,
        ray=out.ray,
        depth=out.depth,
        halted=out.halted,
        **extra,
    )


def halt_at(
    s, si: mi.SurfaceInteraction3f, bsdf, reached: mi.Bool, stop: Optional[Callable], nulls: bool
):
    """Where a walk's `stop` halts it at si. A stylized vertex is a scattering one, so with `nulls`
    a halting lane first passes through the null part (`null_split`) and the stay weight goes into
    the throughput; `s.halted` gains the halted lanes.

    Args:
        s: the loop state (sampler, beta, depth, halted), updated in place.
        si, bsdf, reached: the vertex, its BSDF and the lanes that reached it (mi.Bool).
        stop, nulls: the walk's stop hook (None: never halt); the scene has null parts.

    Returns:
        (lanes that shade si, lanes that pass straight on through a null part, their pass weight).
    """
    here, passes, w_pass = mi.Bool(reached), mi.Bool(False), mi.Spectrum(1.0)
    if stop is not None:
        halt = reached & si.is_valid() & stop(si, s.depth)
        if nulls:
            nullish = halt & mi.has_flag(bsdf.flags(), mi.BSDFFlags.Null)
            passes, w_pass, w_stay = null_split(si, bsdf, s.sampler.next_1d(nullish), nullish)
            halt &= ~passes
            s.beta *= dr.select(nullish & halt, w_stay, 1.0)
        s.halted |= halt
        here &= ~halt
    return here, passes, w_pass


def mis_emission(scene: mi.Scene, emitters: EmitterSampler, s, si: mi.SurfaceInteraction3f,
                 hit: mi.Bool) -> mi.Spectrum:
    """Emission at si (the environment where the ray escaped) on the lanes `hit`, times the
    throughput and MIS-weighted against the light sampling done at the previous vertex.

    Args:
        scene, emitters: the scene and its EmitterSampler.
        s: the loop state (its beta, si_prev, pdf_prev, delta_prev).
        si, hit: the vertex and the lanes whose emission counts (mi.Bool).

    Returns:
        mi.Spectrum.
    """
    emitter = si.emitter(scene)
    hit_em = hit & (emitter != None)  # noqa: E711  (a Dr.Jit pointer comparison)
    ds = mi.DirectionSample3f(scene, si=si, ref=s.si_prev)
    em_pdf = emitters.pdf_direction(s.si_prev, ds, hit_em & ~s.delta_prev)
    w_em = dr.select(s.delta_prev, 1.0, mis_power(s.pdf_prev, em_pdf))
    return s.beta * w_em * emitter.eval(si, hit_em)


def advance(tone, si: mi.SurfaceInteraction3f, bs, depth, active):
    """The anchors.ToneState past the vertex `si`: its shape joins the prefix key, a transmission
    sets the depth's bit, a non-delta event ends the all-delta prefix.

    Args:
        tone: the state before si. si, bs: the vertex and the BSDF sample taken there.
        depth: si's path depth. active: the lanes that scattered at si (the others keep `tone`).

    Returns:
        ToneState.
    """
    depth = mi.UInt32(depth)
    through = mi.has_flag(bs.sampled_type, mi.BSDFFlags.Transmission) & (depth < MAX_BITS)
    bit = mi.UInt32(1) << dr.minimum(depth, MAX_BITS - 1)
    return ToneState(
        key=dr.select(active, combine(tone.key, shape_id(si)), tone.key),
        bits=dr.select(active & through, tone.bits | bit, tone.bits),
        delta=dr.select(
            active, tone.delta & mi.has_flag(bs.sampled_type, mi.BSDFFlags.Delta), tone.delta
        ),
        s0=tone.s0,
    )


def past_area_emitters(scene, ray, pi, active):
    """`hide_emitters` on a camera ray: its first intersection that is not an area light, and the
    ray spawned from the last light it passed (Mitsuba's `skip_area_emitters` returns a distance
    measured from a ray it does not hand back, so the lights are stepped through here).

    Args:
        scene: the scene. ray, pi: the camera ray and its first intersection (preliminary).
        active: the camera lanes (mi.Bool).

    Returns:
        (ray, pi): the ray from the last light passed, and its first intersection.
    """
    def through(ray, pi, skip):
        si = pi.compute_surface_interaction(ray, ray_flags=mi.RayFlags.Minimal, active=skip)
        ray = dr.select(skip, si.spawn_ray(ray.d), ray)
        pi = dr.select(skip, scene.ray_intersect_preliminary(ray, coherent=True, active=skip), pi)
        return ray, pi, skip & pi.is_valid() & (pi.shape.emitter() != None)  # noqa: E711

    skip = active & pi.is_valid() & (pi.shape.emitter() != None)  # noqa: E711
    ray, pi, _ = dr.while_loop(
        (mi.Ray3f(ray), pi, skip), lambda r, p, s: s, through, label="hide emitters"
    )
    return ray, pi
