"""Next-event estimation of the environment guided by light portals (kernel/portal.py): where the
scene has portals and an environment, `EmitterSampler` hands the lanes that picked the
environment to `PortalGuide`. Design: docs/design/portals.md.

A point x is *inside* a portal where it lies on the room's side of the portal's plane (its normal
side) and the portal subtends a solid angle there. From a point inside at least one portal, a
direction is drawn from the mixture

    p(d) = q p_portal(d) + (1 - q) p_env(d)

with q = SHARE: through a portal (chosen among those x is inside, in proportion to the solid angle
each subtends at x, then sampled uniformly in that solid angle: kernel/spherical_rectangle.py),
else by the environment's own `sample_direction`. Choosing in proportion to solid angle makes the
portal part uniform over the portals' solid angles: p_portal(d) = (the number of those portals the
ray from x along d crosses) / (the sum of their solid angles). Where x is inside no portal
(outdoors, or beyond the plane of every window) q is 0 and the lane samples the environment alone,
as without portals. The weight is the environment's radiance along d over p(d). `density` gives
p(d) for any direction and is the very function `sample` computes its sample's density with, so
the density MIS reads for a BSDF sample that escaped is the one next-event estimation would have
drawn it with. Unbiased: the mixture's density is positive wherever the environment's own is.
"""
from __future__ import annotations

from dataclasses import dataclass

from styletrace.gate import dr, mi
from styletrace.kernel import spherical_rectangle

#: the share of light samples sent through the portals where the point is inside one. Half, as
#: Cycles splits portal and map sampling (its background portal and map weights are both 1): the
#: map half keeps what no portal covers (other openings, sky seen past a portal's edge, a sun the
#: map's sampling finds) at the map's own density, so no direction's density drops below half of
#: what it was without portals, and the portal half finds the window at once. The benchmark
#: (benchmarks/portals.py) compares 0.25, 0.5 and 0.75: none wins both of its interiors
#: (docs/design/portals.md).
SHARE = 0.5
#: slack of the crossing test (relative to the distance to the portal plus its half edges): the
#: float32 rounding of a direction sampled at a portal's edge (a few 1e-7 of those lengths) must
#: still count as crossing it, so that the density of a sample includes the portal that drew it
SLACK = 2.0 ** -16
#: just below 1: remapped uniform samples stay in [0, 1)
ONE_MINUS = 1.0 - 2.0 ** -24


@dataclass
class Frame:
    """One portal as the kernel reads it: centre, unit edge axes x and y, unit normal n (into the
    room) as mi.Point3f / mi.Vector3f, and the half edges hx, hy (mi.Float), all width 1 and opaque
    (kernel inputs, not constants: a moved portal reuses the compiled kernel)."""
    center: mi.Point3f
    x: mi.Vector3f
    y: mi.Vector3f
    n: mi.Vector3f
    hx: mi.Float
    hy: mi.Float


@dataclass
class Seen:
    """One portal seen from the lanes' points: the point in the portal's frame (px, py along its
    edges from its centre, h its height above the plane on the room's side) and the solid angle
    the portal subtends there (0 where the point is not inside of it)."""
    px: mi.Float
    py: mi.Float
    h: mi.Float
    omega: mi.Float


def _opaque(value):
    dr.make_opaque(value)
    return value


def frame(portal) -> Frame:
    """The kernel's view of a PortalEmitter.

    Args:
        portal: a kernel.portal.PortalEmitter.

    Returns:
        Frame.
    """
    hx = float((portal.edge_x @ portal.edge_x) ** 0.5)
    hy = float((portal.edge_y @ portal.edge_y) ** 0.5)
    x, y = portal.edge_x / hx, portal.edge_y / hy
    # the edge axes and the normal are orthogonal to float rounding (PortalEmitter refuses shears)
    return Frame(center=_opaque(mi.Point3f(*(float(v) for v in portal.center))),
                 x=_opaque(mi.Vector3f(*(float(v) for v in x))),
                 y=_opaque(mi.Vector3f(*(float(v) for v in y))),
                 n=_opaque(mi.Vector3f(*(float(v) for v in portal.normal))),
                 hx=dr.opaque(mi.Float, hx), hy=dr.opaque(mi.Float, hy))


class PortalGuide:
    """Sampling the environment through portals, and the density of that sampling (module
    docstring).

    Args:
        portals: the scene's PortalEmitters (at least one).
        environment: the scene's environment emitter (`Scene.environment`, not a delta).

    Raises:
        ValueError: no portals.
    """

    def __init__(self, portals: list, environment: mi.Emitter):
        if not portals:
            raise ValueError("PortalGuide needs at least one portal")
        self.env = environment
        self.env_ptr = mi.EmitterPtr(environment)
        self.frames = [frame(p) for p in portals]
        # how far Mitsuba's environments put their sample points (twice the scene's bounding
        # radius, the same from every point): a portal sample's point, which shadow rays aim at
        probe, _ = environment.sample_direction(dr.zeros(mi.Interaction3f, 1),
                                                mi.Point2f(0.5, 0.5), mi.Bool(True))
        self.dist = dr.opaque(mi.Float, float(dr.ravel(probe.dist)[0]))

    def seen(self, p: mi.Point3f) -> list:
        """Every portal seen from the points p.

        Args:
            p: the lanes' points (mi.Point3f).

        Returns:
            list[Seen], one per portal, in `frames` order.
        """
        out = []
        for f in self.frames:
            r = p - f.center
            px, py, h = dr.dot(r, f.x), dr.dot(r, f.y), dr.dot(r, f.n)
            omega = spherical_rectangle.solid_angle(-f.hx - px, f.hx - px, -f.hy - py,
                                                    f.hy - py, -h)
            # inside of the portal: above its plane on the room's side, where it subtends an
            # angle (the float32 formula gives 0 only where the point is in the plane)
            out.append(Seen(px, py, h, dr.select((h > 0.0) & (omega > 0.0), omega, 0.0)))
        return out

    def portal_density(self, seen: list, d: mi.Vector3f) -> mi.Float:
        """p_portal(d): the density of the portal part of the mixture, per unit solid angle.

        Args:
            seen: `seen` of the lanes' points. d: the lanes' unit directions.

        Returns:
            mi.Float; 0 where the points are inside of no portal or d crosses none.
        """
        total = mi.Float(0.0)
        count = mi.Float(0.0)
        for f, s in zip(self.frames, seen):
            total += s.omega
            dn = dr.dot(d, f.n)
            t = s.h / -dn
            u = s.px + t * dr.dot(d, f.x)
            v = s.py + t * dr.dot(d, f.y)
            slack = SLACK * (t + f.hx + f.hy)
            cross = ((s.omega > 0.0) & (dn < 0.0) & (dr.abs(u) <= f.hx + slack)
                     & (dr.abs(v) <= f.hy + slack))
            count += dr.select(cross, 1.0, 0.0)
        return dr.select(total > 0.0, count / total, 0.0)

    def density(self, it: mi.Interaction3f, ds: mi.DirectionSample3f, active: mi.Bool,
                seen: list | None = None) -> mi.Float:
        """The mixture's solid-angle density of the direction ds.d from it.p (module docstring),
        before the environment's selection probability.

        Args:
            it: the shading points. ds: directions that reach the environment (ds.d).
            active: the lanes asked (mi.Bool).
            seen: `seen(it.p)`, where the caller has it.

        Returns:
            mi.Float (0 on inactive lanes).
        """
        seen = self.seen(it.p) if seen is None else seen
        total = sum((s.omega for s in seen), mi.Float(0.0))
        q = dr.select(total > 0.0, SHARE, 0.0)
        env = self.env.pdf_direction(it, ds, active)
        mix = q * self.portal_density(seen, ds.d) + (1.0 - q) * env
        return dr.select(active, mix, 0.0)

    def sample(self, it: mi.Interaction3f, x: mi.Float, y: mi.Float, active: mi.Bool):
        """A direction towards the environment from the mixture, with its weight.

        Args:
            it: the shading points. x, y: a uniform 2D sample per lane (x decides between the
                portals and the environment's own sampling, then picks the portal: reused).
            active: the lanes that sample (mi.Bool).

        Returns:
            (ds mi.DirectionSample3f with the mixture's density in ds.pdf, weight L / pdf
            mi.Spectrum); weight and pdf 0 where there is none.
        """
        seen = self.seen(it.p)
        total = sum((s.omega for s in seen), mi.Float(0.0))
        q = dr.select(total > 0.0, SHARE, 0.0)
        through = active & (x < q)
        x = dr.minimum(dr.select(through, x / q, (x - q) / (1.0 - q)), ONE_MINUS)
        # the portal, in proportion to its solid angle: the last whose cumulative share x passed
        # (its offset in the cumulative sum, its view and its frame, per lane)
        target = x * total
        below = mi.Float(0.0)
        pick = [mi.Float(0.0)] * 4 + [mi.Float(1.0)] + [mi.Vector3f(0.0)] * 3 + [mi.Float(1.0)] * 2
        for f, s in zip(self.frames, seen):
            take = (s.omega > 0.0) & (below <= target)
            this = [below, s.px, s.py, s.h, s.omega, f.x, f.y, f.n, f.hx, f.hy]
            pick = [dr.select(take, a, b) for a, b in zip(this, pick)]
            below += s.omega
        base, px, py, h, omega, ax, ay, an, hx, hy = pick
        u = dr.clip((target - base) / omega, 0.0, ONE_MINUS)
        local = spherical_rectangle.sample(-hx - px, hx - px, -hy - py, hy - py, -h,
                                           mi.Point2f(u, y))
        d_portal = dr.normalize(local.x * ax + local.y * ay + local.z * an)
        # (only a point in the portal's plane makes it not finite, and `seen` leaves those out)
        active &= ~through | dr.all(dr.isfinite(d_portal))

        ds, _ = self.env.sample_direction(it, mi.Point2f(x, y), active & ~through)
        d = dr.select(through, d_portal, ds.d)
        ds.d = d
        ds.p = dr.select(through, dr.fma(d, self.dist, it.p), ds.p)
        ds.n = dr.select(through, -d, ds.n)
        ds.dist = dr.select(through, self.dist, ds.dist)
        ds.time = dr.select(through, it.time, ds.time)
        # (as a DirectionSample3f made from an escaped ray has: the direction alone says where)
        ds.uv = dr.select(through, 0.0, ds.uv)
        ds.delta = mi.Bool(False)
        ds.emitter = dr.select(active, self.env_ptr, dr.zeros(mi.EmitterPtr))
        pdf = self.density(it, ds, active, seen)
        ok = active & (pdf > 0.0)
        ds.pdf = dr.select(ok, pdf, 0.0)
        # the radiance along d as an escaped ray sees it (`vertex.environment`): `eval_direction`
        # would read an envmap's texel from ds.uv, which only its own samples carry
        si = dr.zeros(mi.SurfaceInteraction3f, dr.width(d))
        si.p, si.wi, si.time, si.wavelengths = it.p, -d, it.time, it.wavelengths
        radiance = self.env.eval(si, ok)
        return ds, dr.select(ok, radiance / dr.select(ok, pdf, 1.0), 0.0)

__all__ = ["SHARE", "Frame", "Seen", "PortalGuide", "frame"]
