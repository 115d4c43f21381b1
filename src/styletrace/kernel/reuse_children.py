"""Drawing and storing the children of reuse's vertices.

A child is two samples at its vertex v: a next-event sample (direction wl, E = L_e vis / p_light)
and a BSDF sample (direction wb, density p(wb), and the radiance Li arriving along it: the ordinary
path kernel's, less the first emission it meets at lanes that pool, or the next stylized level's
value with first_n_hits). Children are stored 16 floats each, side by side, for the pool to read
every member's.
"""
from __future__ import annotations

from dataclasses import dataclass

from styletrace.gate import dr, mi
from styletrace.kernel.path import Start, walk
from styletrace.kernel.vertex import Site, depth_limit, environment, mis_power


class Children:
    """The stored children (see the module docstring), 16 floats each, side by side in one flat
    array: a child is read with four 4-float loads instead of 16 scattered gathers (the pool reads
    every child K + 1 times). Layout: wl, E, wb, pdf, Li, and fLi = f_i(wb) Li at the child's own
    vertex (pairwise's own samples).

    Args:
        size: the number of children stored.
    """
    DRJIT_STRUCT = {"data": mi.Float}
    SIZE = 16

    def __init__(self, size: int = 0):
        self.data = dr.zeros(mi.Float, size * self.SIZE)

    def store(self, c, sample, Li, fLi, active):
        """Store children at flat indices c.

        Args:
            c: the flat child indices (mi.UInt32).
            sample: (wl mi.Vector3f, E mi.Spectrum, wb mi.Vector3f, pdf mi.Float).
            Li, fLi: the radiance along wb, and f(wb) Li at the child's own vertex (mi.Spectrum).
            active: the lanes that store (mi.Bool).
        """
        wl, E, wb, pdf = sample
        packets = (mi.Vector4f(wl.x, wl.y, wl.z, E[0]), mi.Vector4f(E[1], E[2], wb.x, wb.y),
                   mi.Vector4f(wb.z, pdf, Li[0], Li[1]), mi.Vector4f(Li[2], fLi[0], fLi[1], fLi[2]))
        for t, value in enumerate(packets):
            dr.scatter(self.data, value, c * 4 + t, active)

    def load(self, c, active):
        """The children at flat indices c.

        Args:
            c: the flat child indices (mi.UInt32).
            active: the lanes that read (mi.Bool).

        Returns:
            (wl, E, wb, pdf, Li, fLi) as `store` took them.
        """
        a, b, d, e = (dr.gather(mi.Vector4f, self.data, c * 4 + t, active) for t in range(4))
        return (
            mi.Vector3f(a.x, a.y, a.z),
            mi.Spectrum(a.w, b.x, b.y),
            mi.Vector3f(b.z, b.w, d.x),
            d.y,
            mi.Spectrum(d.z, d.w, e.x),
            mi.Spectrum(e.y, e.z, e.w),
        )

    def directions(self):
        """wl of every stored child (zero where none was stored)."""
        first = dr.arange(mi.UInt32, dr.width(self.data) // self.SIZE) * self.SIZE
        return mi.Vector3f(*(dr.gather(mi.Float, self.data, first + k) for k in range(3)))


@dataclass(frozen=True)
class Slab:
    """Stored children with M slots per lane: child j of lane i at kids[i * M + j]."""
    kids: Children
    M: int


@dataclass(frozen=True)
class Parents:
    """The vertices children are drawn at, per lane: the interaction, its BSDF, the lanes that draw
    (`active`) and those that pool (whose light is split by technique)."""
    si: mi.SurfaceInteraction3f
    bsdf: mi.BSDFPtr
    active: mi.Bool
    pool: mi.Bool


@dataclass(frozen=True)
class Span:
    """Which children `draw` draws: first .. last - 1 of each of the lanes `lane` (at most J of
    them), stored at lane * M + j of `slab`."""
    first: mi.UInt32
    last: mi.UInt32
    J: int
    slab: Slab
    lane: mi.UInt32


class Draw:
    """One child's two samples at its parent's vertex (its lane `on`): a next-event sample
    (direction ds.d, E) and a BSDF sample (direction wb, density bs.pdf, weight w_b) with the ray to
    what it reaches (ray2, pi2). At a non-last level of first_n_hits (`nested`) next-event
    estimation samples delta lights only, as `bounce.bounce`: the BSDF sample reaches every other
    emitter, which the next level stylizes.

    Args:
        scope, smp: the render's Scope and the lanes' random streams (LaneSampler).
        parents: the vertices drawn at. on: the lanes that draw this child (mi.Bool).
        depth: the parents' path depth (0: the first hit).
        nested: the parents are a non-last first_n_hits level.
    """

    def __init__(self, scope, smp, parents: Parents, on, depth: int, nested: bool):
        si, bsdf = parents.si, parents.bsdf
        step = on & (depth + 1 < depth_limit(scope.settings.max_depth))
        to_light = step & mi.has_flag(bsdf.flags(), mi.BSDFFlags.Smooth)
        ds, em_weight = scope.emitters.sample_direction(si, smp.next_2d(), to_light)
        to_light &= ds.pdf != 0.0
        if nested:
            to_light &= ds.delta
        val, pdf_l, bs, w_b = bsdf.eval_pdf_sample(
            mi.BSDFContext(), si, si.to_local(ds.d), smp.next_1d(), smp.next_2d(), step
        )
        # Lanes that pool split the light by technique, not by MIS: next-event estimation takes all
        # the emission it can reach (weight 1) and the BSDF sample none of the first emission it
        # meets (pdf 0 below), so the two pooled sums are each unbiased whatever the neighbours'
        # densities; MIS weights computed at different vertices would not add up to one.
        # (first_n_hits splits them so already.)
        w_nee = dr.select(ds.delta | parents.pool, 1.0, mis_power(ds.pdf, pdf_l))
        self.to_light, self.val, self.ds, self.bs, self.w_b = to_light, val, ds, bs, w_b
        self.E = dr.select(to_light, em_weight * w_nee, 0.0)
        self.wb = si.to_world(bs.wo)
        self.go = step & (dr.max(w_b) > 0)
        self.ray2 = si.spawn_ray(self.wb)
        self.pi2 = scope.scene.ray_intersect_preliminary(self.ray2, coherent=False, active=self.go)

    def next_vertex(self):
        """(si2, hit2): the surface the BSDF sample reaches, where it reaches one."""
        si2 = self.pi2.compute_surface_interaction(
            self.ray2, ray_flags=mi.RayFlags.All, active=self.go
        )
        return si2, self.go & si2.is_valid()

    def seen(self, scene, si2, hit2, value):
        """The radiance Li along the BSDF sample: `value` where it hit a surface, else the
        environment; 0 where the sample was not taken.

        Args:
            scene: the scene. si2, hit2: `next_vertex`'s interaction and hit mask.
            value: the radiance leaving si2 towards the parent (mi.Spectrum).

        Returns:
            mi.Spectrum.
        """
        return dr.select(self.go, dr.select(hit2, value, environment(scene, si2, self.go)), 0.0)

    def store(self, kids, at, Li, on):
        """Store the child at flat index `at` with its Li (where `on` and its estimate is finite).

        Args:
            kids: the Children. at: the flat index (mi.UInt32).
            Li: the radiance along the BSDF sample (mi.Spectrum). on: the lanes that store.

        Returns:
            The child's ordinary estimate x (mi.Spectrum), 0 where not `on` or not finite.
        """
        go, bs = self.go, self.bs
        x = dr.select(self.to_light, self.val * self.E, 0.0) + dr.select(go, self.w_b * Li, 0.0)
        ok = on & dr.all(dr.isfinite(x))
        kids.store(at, (self.ds.d, self.E, self.wb, dr.select(go, bs.pdf, 0.0)), Li,
                   dr.select(go, self.w_b * bs.pdf * Li, 0.0), ok)
        return dr.select(ok, x, 0.0)


def draw(scope, lanes, parents: Parents, span: Span, depth: int = 0):
    """Draw the children `span` names at the `parents` and store them.

    Args:
        scope, lanes: the render's Scope and the lanes' random streams (advanced in place).
        parents: the first hits, or with `depth` 1 second-level vertices whose children are
            ordinary paths. span: which children, and where they are stored.
        depth: the parents' stylized level and path depth (0 or 1).

    Returns:
        Per lane, the sum of its children's ordinary estimates (next-event plus BSDF-sampled
        radiance, emission at v left out; mi.Spectrum).
    """
    s, scene, integ = scope.settings, scope.scene, scope.integ
    nested = s.stylize == "first_n_hits" and s.stylize_depth > depth + 1
    si, pool, M = parents.si, parents.pool, span.slab.M

    def body(i, smp, total):
        j = span.first + i
        on = parents.active & (j < span.last)
        c = Draw(scope, smp, parents, on, depth, nested)
        # the level-1 vertex, stylized by the ordinary tree (deeper levels first), or the sky
        if nested:
            si2, hit2 = c.next_vertex()
            site = Site(c.pi2, si2, c.ray2, mi.UInt32(depth + 1))
            Li = c.seen(scene, si2, hit2, integ.stylized(depth + 1, smp, site, hit2))
        else:
            delta = mi.has_flag(c.bs.sampled_type, mi.BSDFFlags.Delta)
            came_from = (dr.detach(si, True), dr.select(pool, 0.0, c.bs.pdf), delta & ~pool)
            start = Start(c.pi2, c.ray2, depth + 1, came_from=came_from)
            w = walk(integ.walk_config, smp, start, c.go)
            Li = dr.select(c.go, w.L, 0.0)
        return i + 1, smp, total + c.store(span.slab.kids, span.lane * M + j, Li, on)

    _, lanes_out, total = dr.while_loop(
        (mi.UInt32(0), lanes, mi.Spectrum(0.0)),
        lambda i, smp, t: i < span.J,
        body,
        label="styletrace reuse children",
    )
    lanes.rng = lanes_out.rng
    return total
