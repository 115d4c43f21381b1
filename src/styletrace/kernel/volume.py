"""The path kernel in scenes with participating media: `walk` of path.py, but along rays
through media.

    w = volume_walk(cfg, sampler, Start(pi, ray, medium=medium, flight=True), active, hooks)
    tr = transmittance(scene, sampler, it, ds, medium, channel, active)   # towards a light

Mitsuba's `volpath` estimator: delta tracking from the medium's majorant in one hero colour
channel per path, next-event estimation with ratio-tracked transmittance through media and null
surfaces, MIS against phase and BSDF sampling; depth counts real scatterings. `volume_walk` has
path.walk's signature. A stylized vertex is a surface one, or with `Hooks.halt_in_medium` the
first real collision in a medium (`Collision`: g's argument there is albedo x in-scattered
radiance). `Start.flight`: sample the medium along the first ray; `Start.delta`: the start vertex
samples delta lights only; `Start.hide`: no emission before the first scattering;
`Start.collision`: its lanes start by scattering at that collision. Design:
docs/design/participating_media.md.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Optional

from styletrace.gate import dr, mi
from styletrace.kernel.anchors import ToneState, combine
from styletrace.kernel.lines import Edge, LineState
from styletrace.kernel.path import (
    NO_HOOKS,
    Hooks,
    Start,
    Walk,
    WalkConfig,
    advance,
    finished,
    halt_at,
    mis_emission,
)
from styletrace.kernel.vertex import depth_limit, mis_power, opaque_part, opaque_share


def channel_of(c: mi.Spectrum, channel: mi.UInt32) -> mi.Float:
    """The value of colour c in the path's free-flight channel.

    Args:
        c: a colour (mi.Spectrum). channel: the channel per lane (mi.UInt32: 0, 1 or 2).

    Returns:
        mi.Float.
    """
    return dr.select(channel == 0, c[0], dr.select(channel == 1, c[1], c[2]))


def free_flight_weight(medium, mei, t_surface, channel, active) -> mi.Spectrum:
    """Transmittance over the channel's free-flight density up to the collision or the surface.

    Args:
        medium: the medium per lane (mi.MediumPtr). mei: the sampled medium interaction.
        t_surface: the distance to the next surface (mi.Float; inf: none).
        channel: the free-flight channel (mi.UInt32). active: the lanes in a medium (mi.Bool).

    Returns:
        mi.Spectrum: 1 where not active, 0 where the channel's density is 0.
    """
    st = dr.zeros(mi.SurfaceInteraction3f)
    st.t = t_surface
    tr, pdf = medium.transmittance_eval_pdf(mei, st, active)
    p = channel_of(pdf, channel)
    return dr.select(active, dr.select(p > 0, tr / p, 0.0), 1.0)


def medium_vertex(mei: mi.MediumInteraction3f) -> mi.Interaction3f:
    """A medium collision as a plain interaction (no normal), for emitter sampling and densities.

    Args:
        mei: the collision (mi.MediumInteraction3f).

    Returns:
        mi.Interaction3f.
    """
    return mi.Interaction3f(t=mei.t, time=mei.time, wavelengths=mei.wavelengths, p=mei.p)


@dataclass
class Collision:
    """A stylized vertex in a medium (a Dr.Jit PyTree): the real collision a walk halted at.

    inside: the lanes whose vertex it is (the others stand at a surface or none); mei: the
    collision; albedo: sigma_s / sigma_t there per channel (0 where sigma_t is), the share of the
    in-scattered radiance the collision sends on. The halted walk's throughput times albedo is
    volpath's weight at the collision, so g sees a radiance, as at a surface.
    """
    inside: mi.Bool
    mei: mi.MediumInteraction3f
    albedo: mi.Spectrum


def no_collision(width: int) -> Collision:
    """A Collision with no lane inside.

    Args:
        width: the number of lanes.

    Returns:
        Collision.
    """
    return Collision(inside=dr.zeros(mi.Bool, width), mei=dr.zeros(mi.MediumInteraction3f, width),
                     albedo=dr.zeros(mi.Spectrum, width))


def collision_site(si: mi.SurfaceInteraction3f, collision: Collision,
                   ray: mi.Ray3f) -> mi.SurfaceInteraction3f:
    """The interaction a style reads at a stylized vertex: si at surfaces, at a collision in a
    medium one of no shape (no BSDF, no emitter) at the collision's point and time, its normal
    towards where the ray came from.

    Args:
        si: the surface interactions. collision: the Collision. ray: the ray that reached them.

    Returns:
        mi.SurfaceInteraction3f.
    """
    m = collision.mei
    at = dr.zeros(mi.SurfaceInteraction3f, dr.width(ray.d))
    at.t, at.time, at.wavelengths, at.p = m.t, m.time, m.wavelengths, m.p
    at.n = mi.Normal3f(-ray.d)
    at.sh_frame = mi.Frame3f(-ray.d)
    at.wi = mi.Vector3f(0.0, 0.0, 1.0)
    return dr.select(collision.inside, at, si)


@dataclass
class ShadowState:
    sampler: Any
    ray: mi.Ray3f
    medium: Any
    tr: mi.Spectrum
    active: mi.Bool


def transmittance(scene: mi.Scene, sampler, it: mi.Interaction3f, ds: mi.DirectionSample3f, medium,
                  channel: mi.UInt32, active: mi.Bool) -> mi.Spectrum:
    """Ratio-tracking estimate of the transmittance from `it` to the light point ds.p: through media
    (null collisions weigh sigma_n over the channel's density) and through surfaces by their null
    transmission (0 at opaque ones: an occlusion test).

    Args:
        scene, sampler: the scene and the lane's random stream.
        it, ds: the shading point and the light sample (mi.DirectionSample3f).
        medium: the medium the shadow ray starts in (mi.MediumPtr).
        channel: the free-flight channel (mi.UInt32). active: the lanes that test (mi.Bool).

    Returns:
        mi.Spectrum, 0 where not active.
    """
    state = ShadowState(sampler=sampler, ray=it.spawn_ray_to(ds.p), medium=mi.MediumPtr(medium),
                        tr=mi.Spectrum(1.0), active=mi.Bool(active))

    def body(s: ShadowState):
        pi = scene.ray_intersect_preliminary(s.ray, coherent=False, active=s.active)
        t_surf = dr.select(pi.is_valid(), pi.t, dr.inf)
        in_med = s.active & (s.medium != None)  # noqa: E711  (a Dr.Jit pointer comparison)
        mei = s.medium.sample_interaction(s.ray, s.sampler.next_1d(in_med), channel, in_med)
        mei.t = dr.select(mei.t > t_surf, dr.inf, mei.t)
        s.tr *= free_flight_weight(s.medium, mei, dr.minimum(t_surf, s.ray.maxt), channel, in_med)
        coll = in_med & mei.is_valid()
        s.tr = dr.select(coll, s.tr * mei.sigma_n, s.tr)
        ray_coll = mi.Ray3f(s.ray)
        ray_coll.o, ray_coll.maxt = mei.p, s.ray.maxt - mei.t

        surf = s.active & ~coll & pi.is_valid()
        si = pi.compute_surface_interaction(s.ray, ray_flags=mi.RayFlags.All, active=surf)
        s.tr = dr.select(surf, s.tr * si.bsdf(s.ray).eval_null_transmission(si, surf), s.tr)
        s.medium = dr.select(surf & si.is_medium_transition(), si.target_medium(s.ray.d), s.medium)
        s.ray = dr.select(coll, ray_coll, dr.select(surf, si.spawn_ray_to(ds.p), s.ray))
        s.active = (coll | surf) & dr.any(s.tr != 0.0)
        return (s,)

    (out,) = dr.while_loop(
        (state,), lambda s: s.active, body, label="styletrace shadow transmittance"
    )
    return dr.select(active, out.tr, 0.0)


@dataclass
class VolumeState:
    """The loop state of `volume_walk` (path.PathState plus the medium and the
    free-flight switch)."""
    sampler: Any
    pi: mi.PreliminaryIntersection3f     # the next surface along `ray` (its t measured from ray.o)
    ray: mi.Ray3f
    medium: Any                          # MediumPtr: where `ray` travels (None: vacuum)
    flight: mi.Bool                      # sample the medium along `ray` before reaching `pi`
    active: mi.Bool
    depth: mi.UInt32
    L: mi.Spectrum
    beta: mi.Spectrum
    eta: mi.Float
    si_prev: mi.Interaction3f            # last real scattering vertex, for the emitter density
    pdf_prev: mi.Float
    delta_prev: mi.Bool                  # its direction had no competing light sample: full weight
    halted: mi.Bool
    first: mi.Bool                       # at the starting vertex
    lines: Optional[Any] = None          # lines.LineState where feature lines are on
    tone: Optional[Any] = None           # anchors.ToneState where a style reads image coordinates
    collision: Optional[Any] = None      # Collision where the walk halts in media


def volume_walk(
    cfg: WalkConfig, sampler, start: Start, active: mi.Bool, hooks: Hooks = NO_HOOKS
) -> Walk:
    """path.walk through participating media (module docstring).

    Args:
        cfg, sampler: the render's WalkConfig and the lane's random stream.
        start: where the walk starts (its medium, flight, delta and hide apply here).
        active: the lanes that walk (mi.Bool). hooks: as path.walk's.

    Returns:
        A path.Walk, with the medium each lane stands in.
    """
    scene, emitters, nulls, rr_depth = cfg.scene, cfg.emitters, cfg.nulls, cfg.rr_depth
    stop, skip_emitter, lines, tone = hooks.stop, hooks.skip_emitter, hooks.lines, hooks.tone
    halt_in_medium, start_at = hooks.halt_in_medium, start.collision
    opaque_start, delta_start, hide_first = start.opaque, start.delta, start.hide
    ctx, pctx = mi.BSDFContext(), mi.PhaseFunctionContext(None)
    limit = depth_limit(cfg.max_depth)
    channel = mi.UInt32(dr.minimum(sampler.next_1d(active) * 3.0, 2.0))

    state = VolumeState(
        sampler=sampler,
        pi=mi.PreliminaryIntersection3f(start.pi),
        ray=mi.Ray3f(start.ray),
        medium=dr.select(active, mi.MediumPtr(start.medium), mi.MediumPtr(None)),
        flight=mi.Bool(start.flight),
        active=mi.Bool(active),
        depth=mi.UInt32(start.depth),
        L=mi.Spectrum(0.0),
        beta=mi.Spectrum(1.0),
        eta=mi.Float(1.0),
        si_prev=dr.zeros(mi.Interaction3f),
        pdf_prev=mi.Float(1.0),
        delta_prev=mi.Bool(True),
        halted=mi.Bool(False),
        first=mi.Bool(True),
        lines=None if lines is None else lines[1],
        tone=tone,
        collision=None if halt_in_medium is None else no_collision(dr.width(start.ray.d)),
    )

    def body(s: VolumeState):
        # lanes that start at a collision scatter there first, with no flight before it
        forced = None if start_at is None else s.first & s.active & start_at.inside
        # ---- the medium between the ray's origin and the surface `pi` (volpath's delta tracking)
        in_med = s.active & s.flight & (s.medium != None)  # noqa: E711
        if forced is not None:
            in_med &= ~forced
        mei = s.medium.sample_interaction(s.ray, s.sampler.next_1d(in_med), channel, in_med)
        t_surf = dr.select(s.pi.is_valid(), s.pi.t, dr.inf)
        mei.t = dr.select(mei.t > t_surf, dr.inf, mei.t)
        s.beta *= free_flight_weight(s.medium, mei, t_surf, channel, in_med)
        real = in_med & mei.is_valid()
        if forced is not None:
            mei = dr.select(forced, start_at.mei, mei)
            real |= forced
        majorant_c, sigma_t_c = (
            channel_of(mei.combined_extinction, channel),
            channel_of(mei.sigma_t, channel),
        )
        null_coll = real & (s.sampler.next_1d(real) >= sigma_t_c / majorant_c)
        if forced is not None:
            null_coll &= ~forced
        sigma_n_c = channel_of(mei.sigma_n, channel)
        s.beta *= dr.select(
            null_coll, dr.select(sigma_n_c > 0, mei.sigma_n * majorant_c / sigma_n_c, 0.0), 1.0
        )
        scat = real & ~null_coll
        depth_m = s.depth + 1
        scat &= depth_m < limit                  # a collision past the last depth ends the path
        beta_m = s.beta * dr.select(sigma_t_c > 0, mei.sigma_s * majorant_c / sigma_t_c, 0.0)
        if forced is not None:  # the halted walk's weight times albedo was beta_m (Collision)
            beta_m = dr.select(forced, s.beta * start_at.albedo, beta_m)
        halt_m = None
        if halt_in_medium is not None:
            halt_m = scat & halt_in_medium(s.depth)
            scat &= ~halt_m
            s.halted |= halt_m
            # beta_m = weight x albedo: the weight is the throughput, the albedo goes inside g
            weight_m = s.beta * dr.select(sigma_t_c > 0, majorant_c * mei.sigma_t / sigma_t_c, 0.0)
            c = s.collision
            s.collision = Collision(
                inside=c.inside | halt_m,
                mei=dr.select(halt_m, mei, c.mei),
                albedo=dr.select(
                    halt_m, dr.select(mei.sigma_t > 0, mei.sigma_s / mei.sigma_t, 0.0), c.albedo
                ),
            )
        it_m = medium_vertex(mei)

        # ---- the surface, for lanes whose flight reached it (or that travel in no medium)
        at_surf = s.active & ~real
        si = s.pi.compute_surface_interaction(s.ray, ray_flags=mi.RayFlags.All, active=at_surf)
        bsdf = si.bsdf(s.ray)
        here, passes, w_pass = halt_at(s, si, bsdf, at_surf, stop, nulls)
        s.L += mis_emission(scene, emitters, s, si, here & (s.depth > 0) if hide_first else here)

        # the BSDF is sampled at the last depth too: a null component sampled there goes on at the
        # same depth
        sample_s = here & ~passes & si.is_valid()
        active_s = sample_s & (s.depth + 1 < limit)

        # ---- next-event estimation: one light sample at the medium collision or the surface
        sample_m = scat & mei.medium.use_emitter_sampling()
        em_on = sample_m | (active_s & mi.has_flag(bsdf.flags(), mi.BSDFFlags.Smooth))
        it = dr.select(scat, it_m, mi.Interaction3f(si))
        ds, em_weight = emitters.sample_direction(
            it, s.sampler.next_2d(em_on), em_on, visible=False
        )
        em_on &= ds.pdf != 0.0
        if skip_emitter is not None:
            em_on &= ~skip_emitter(ds)
        if delta_start:
            em_on &= ~s.first | ds.delta | scat
        to_light = dr.select(at_surf & si.is_medium_transition(), si.target_medium(ds.d), s.medium)
        tr = transmittance(scene, s.sampler, it, ds, to_light, channel, em_on)
        phase = mei.medium.phase_function()
        phase_val, phase_pdf = phase.eval_pdf(pctx, mei, ds.d, sample_m)
        wo = si.to_local(ds.d)
        u1 = s.sampler.next_1d(sample_s)
        # the stylized starting vertex samples its opaque part alone (opaque_share)
        if nulls and opaque_start:
            keep = dr.select(s.first, opaque_share(si, bsdf, sample_s & s.first), 1.0)
            u1 = dr.select(s.first, u1 * keep, u1)
        bsdf_val, bsdf_pdf, bs, bsdf_weight = bsdf.eval_pdf_sample(
            ctx, si, wo, u1, s.sampler.next_2d(sample_s), sample_s
        )
        scale = mi.Spectrum(1.0)
        # the opaque part's f (NEE) and pdfs; the sample's weight is that part's
        if nulls and opaque_start:
            scale = dr.select(s.first, opaque_part(si, bsdf, sample_s & s.first), 1.0)
            ok = keep > 0
            bsdf_pdf = dr.select(ok, bsdf_pdf / dr.select(ok, keep, 1.0), 0.0)
            bs.pdf = dr.select(ok, bs.pdf / dr.select(ok, keep, 1.0), 0.0)
            bsdf_weight[~ok | (s.first & mi.has_flag(bs.sampled_type, mi.BSDFFlags.Null))] = 0.0
        f_val = dr.select(scat, phase_val, scale * bsdf_val)
        f_pdf = dr.select(scat, phase_pdf, bsdf_pdf)
        w_nee = dr.select(ds.delta, 1.0, mis_power(ds.pdf, f_pdf))
        s.L += dr.select(
            em_on, dr.select(scat, beta_m, s.beta) * f_val * em_weight * tr * w_nee, 0.0
        )

        # ---- the next ray: phase sample in the medium, BSDF sample (or straight on) at the surface
        wo_m, phase_weight, phase_pdf_m = phase.sample(
            pctx, mei, s.sampler.next_1d(scat), s.sampler.next_2d(scat), scat
        )
        scat &= phase_pdf_m > 0.0
        null_s = passes | mi.has_flag(bs.sampled_type, mi.BSDFFlags.Null)
        go_s = (sample_s & (null_s | active_s)) | (here & passes)
        ray_s = dr.select(passes, si.spawn_ray(s.ray.d), si.spawn_ray(si.to_world(bs.wo)))
        beta_s = dr.select(passes, s.beta * w_pass, s.beta * bsdf_weight)
        delta_s = dr.select(null_s, s.delta_prev, mi.has_flag(bs.sampled_type, mi.BSDFFlags.Delta) |
                            (s.first & delta_start))

        ray_next = dr.select(scat, mei.spawn_ray(wo_m), ray_s)
        beta_next = dr.select(scat, beta_m * phase_weight, beta_s)
        depth_next = dr.select(scat, depth_m, s.depth + dr.select(null_s, 0, 1))
        go = scat | go_s
        s.eta *= dr.select(go_s & ~null_s, bs.eta, 1.0)
        real_s = go_s & ~null_s
        s.si_prev = dr.select(
            scat, it_m, dr.select(real_s, mi.Interaction3f(dr.detach(si, True)), s.si_prev)
        )
        s.pdf_prev = dr.select(scat, phase_pdf_m, dr.select(real_s, bs.pdf, s.pdf_prev))
        s.delta_prev = dr.select(
            scat, ~mei.medium.use_emitter_sampling(), dr.select(go_s, delta_s, s.delta_prev)
        )
        s.medium = dr.select(
            go_s & si.is_medium_transition(), si.target_medium(ray_next.d), s.medium
        )
        # the prefix the next vertex's image coordinate is searched with (anchors.py)
        if tone is not None:
            s.tone = scattered_in_medium(advance(s.tone, si, bs, s.depth, real_s), scat)

        # roulette after each scattering, from depth rr_depth + 1 on (volpath's)
        beta_max = dr.max(beta_next)
        go &= beta_max != 0.0
        q = dr.minimum(beta_max * dr.square(s.eta), 0.95)
        roulette = go & (depth_next > rr_depth)
        beta_next[roulette] *= dr.rcp(q)
        go &= ~roulette | (s.sampler.next_1d(roulette) < q)

        pi_next = scene.ray_intersect_preliminary(ray_next, coherent=False, active=go)
        # a line on the edge a surface scattering starts absorbs the path (lines.py)
        if lines is not None:
            seen, after = lines[0].edge(
                scene, s.sampler, s.lines, si, bs, Edge(ray_next, pi_next, depth_next), go & real_s
            )
            s.L += dr.select(seen.fired, beta_next * seen.color, 0.0)
            go &= ~seen.fired
            s.lines = lines_past(after, pi_next, go & go_s & null_s, scat)
        # null collisions move the origin along the same ray; halted lanes keep their vertex
        moved = mi.Ray3f(s.ray)
        moved.o = mei.p
        pi_moved = mi.PreliminaryIntersection3f(s.pi)
        pi_moved.t = s.pi.t - mei.t
        s.pi = dr.select(go, pi_next, dr.select(null_coll, pi_moved, s.pi))
        s.ray = dr.select(go, ray_next, dr.select(null_coll, moved, s.ray))
        s.beta = dr.select(go, beta_next, s.beta if halt_m is None
                           else dr.select(halt_m, weight_m, s.beta))
        s.depth = dr.select(go, depth_next, s.depth)
        s.flight = mi.Bool(True)
        s.first = mi.Bool(False)
        s.active = go | null_coll
        return (s,)

    (out,) = dr.while_loop((state,), lambda s: s.active, body, label="styletrace volumetric path")
    # as at the end of path.walk: a sample that is not finite is dropped
    return finished(out, medium=out.medium, lines=out.lines, tone=out.tone,
                    collision=out.collision)


def scattered_in_medium(tone: ToneState, active: mi.Bool) -> ToneState:
    """The anchors.ToneState past a scattering in a medium. The anchor paths reflect or refract at
    surfaces only and cannot follow it: it ends the all-delta prefix and joins the prefix key as no
    shape does, so no anchor matches and the coordinate takes its fallbacks (anchors.py).

    Args:
        tone: the state before. active: the lanes that scattered in a medium (mi.Bool).

    Returns:
        ToneState.
    """
    key = combine(tone.key, mi.UInt32(0xFFFFFFFF))  # a shape id + 1 that no shape has: 0
    return ToneState(
        key=dr.select(active, key, tone.key), bits=tone.bits, delta=tone.delta & ~active, s0=tone.s0
    )


def lines_past(state: LineState, pi: mi.PreliminaryIntersection3f, passed: mi.Bool,
               scattered: mi.Bool) -> LineState:
    """The lines.LineState past a null surface or a scattering in a medium.

    Args:
        state: the state after the edge's test. pi: the next surface along the edge.
        passed: the edge goes on through the surface (its lines were tested through it), so its
            length grows by the next segment's.
        scattered: a phase function is no mirror, so, as after a diffuse vertex, no later edge is
            tested.

    Returns:
        LineState.
    """
    D = dr.select(passed, state.D + dr.select(pi.is_valid(), pi.t, dr.inf), state.D)
    return LineState(D=D, alive=state.alive & ~scattered, angle=state.angle, spread=state.spread)
