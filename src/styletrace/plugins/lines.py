"""Physically based feature lines on path edges (West 2021, "Physically-Based Feature Line Rendering",
ACM TOG 40(6) 246; as described in West, Mukherjee and Yue 2026, "Lifting Lines and Tone").

A line is detected on an *edge* of a camera path (the camera ray is edge 0, the ray leaving the first
hit edge 1, ...) for edges 0 .. `depth` - 1, and only while every vertex before the edge scattered
non-diffusely (a line is seen in a mirror, through glass, out of focus; not in diffuse reflection).
Where a line is found the path absorbs: it returns throughput x line colour and ends.

Detection: N auxiliary rays in a cone around the base edge, one stencil point (a, b) per ray, uniform
and independent in a disc of radius `width` / 2 pixels (so a line is `width` pixels wide, and a line
is found by each ray with the same probability q: coverage 1 - (1 - q)^N).
- Camera edge: o_j = o + a (o_x - o) + b (o_y - o), d_j = normalize(d + a (d_x - d) + b (d_y - d)) from
  the camera ray's own differentials (one-pixel ones: Mitsuba scales them by 1/sqrt(spp)), so depth of
  field is shared.
- Later edges: the cone's half-angle per pixel (`angle`, |d_x - d| at the camera) and the accumulated
  path length D from the camera set the stencil: origins on the vertex's tangent plane at lateral offset
  angle * D * (a, b), directions d + angle * (a, b). After a flat mirror this is exactly the cone of the
  mirrored camera, so a reflected line keeps its screen width.
Tests between the base hit q and an auxiliary hit s (any one fires; each can be switched off):
- silhouette: one of the two hits a surface, the other escapes;
- boundary: both hit, on different shapes (as the loaded scene holds them: Mitsuba merges meshes that
  share a BSDF into one shape when it loads a scene, so their seams draw nothing here);
- crease: 1 - |n_q . n_s| > `crease` (geometric normals; |.| so flipped normals do not fire);
- albedo: |lum(albedo_q) - lum(albedo_s)| > `albedo`;
- depth: the distance of either point from the other's tangent plane exceeds `slope` times the cone's
  radius at q (slope-aware: any plane, however slanted, gives 0).
The line point is the nearest (along its ray) of the points of the pairs that fire; its world y picks the
colour of a `gradient`. `objects`: ids of the shapes that draw lines (empty: all); a pair draws where
either of its hits is on one of them.

`mode` expectation (LLaT, West, Mukherjee and Yue 2026): lines as a style of expectation,
    g = (1 - w) c + w L,  w = E[m]^k,
m(u, v) = "no line between the stencil points u and v" for a random pair of auxiliary rays (the same tests
between their two hits). The product of k independent metric samples estimates E[m]^k without bias, and,
m being binary, it is 0 as soon as one pair fires: the sample is then c and L is never traced (the
integrator masks those lanes off). k is the opacity control. The absorbing mode is the same composition
with N rays tested against the base ray, so both share `Seen` and the integrator's and walk's hooks.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import drjit as dr
import mitsuba as mi

from ..errors import SceneError

TESTS = ("silhouette", "boundary", "crease", "albedo", "depth")
DEFAULT_TESTS = ("silhouette", "boundary", "crease", "depth")
MODES = ("absorb", "expectation")


@dataclass(frozen=True)
class LineSettings:
    """Parsed in `settings.parse` from the `line_*` integrator properties, whose declarations
    (`settings.PROPERTIES`) hold the defaults, bounds and docs: none are repeated here."""
    width: float                             # pixels, the line's full width
    samples: int                             # N auxiliary rays per edge
    depth: int                               # edges 0 .. depth - 1 (1: the camera ray only)
    tests: tuple[str, ...]
    crease: float
    albedo: float
    slope: float
    color: tuple[float, float, float]
    gradient: tuple | None                   # ((r,g,b), (r,g,b), y0 or None, y1 or None)
    objects: tuple[str, ...]
    mode: str                                # "absorb" or "expectation" (LLaT): k stencil pairs
    k: int

    def describe(self) -> str:
        return (f"lines(width={self.width}, samples={self.samples}, depth={self.depth}, tests={','.join(self.tests)})")


class LineState:
    """What a path carries for lines: accumulated length from the camera, whether no diffuse vertex was
    met yet, and the cone's angle per pixel (from the camera ray's differentials)."""
    DRJIT_STRUCT = {"D": mi.Float, "alive": mi.Bool, "angle": mi.Float}

    def __init__(self, D=None, alive=None, angle=None):
        self.D = mi.Float(0.0) if D is None else D
        self.alive = mi.Bool(True) if alive is None else alive
        self.angle = mi.Float(0.0) if angle is None else angle


@dataclass
class Seen:
    fired: mi.Bool
    color: mi.Color3f


class Lines:
    """The line settings bound to one scene for one trace (shape pointers, the gradient's y range)."""

    def __init__(self, settings: LineSettings, scene: mi.Scene):
        self.s = settings
        self.draw_all = not settings.objects
        # positions, geometric normals and shapes are all the tests need; the albedo test evaluates textures
        self.flags = mi.RayFlags.All if "albedo" in settings.tests else mi.RayFlags.Minimal
        self.shapes = []
        if settings.objects:
            by_id = {shape.id(): shape for shape in scene.shapes()}
            missing = [i for i in settings.objects if i not in by_id]
            if missing:
                raise SceneError(f"bad value {missing[0]!r} in 'line_objects': the scene's shape ids are "
                                 f"{', '.join(sorted(k for k in by_id if k)) or 'none'}")
            self.shapes = [mi.ShapePtr(by_id[i]) for i in settings.objects]
        if settings.gradient is not None:
            c0, c1, y0, y1 = settings.gradient
            box = scene.bbox()
            self.y0 = float(box.min.y) if y0 is None else y0
            self.y1 = float(box.max.y) if y1 is None else y1

    # ---- what a line looks like ---------------------------------------------------------------
    def color(self, p: mi.Point3f) -> mi.Color3f:
        if self.s.gradient is None:
            return mi.Color3f(*self.s.color)
        c0, c1 = mi.Color3f(*self.s.gradient[0]), mi.Color3f(*self.s.gradient[1])
        t = dr.clip((p.y - self.y0) / max(self.y1 - self.y0, 1e-12), 0.0, 1.0)
        return dr.lerp(c0, c1, t)

    def _draws(self, si) -> mi.Bool:
        if self.draw_all:
            return si.is_valid()
        mask = mi.Bool(False)
        for ptr in self.shapes:
            mask |= si.shape == ptr
        return si.is_valid() & mask

    # ---- the edges --------------------------------------------------------------------------------
    def camera(self, scene, sampler, ray: mi.RayDifferential3f, spp: int, active: mi.Bool):
        """Edge 0, from the camera ray's differentials: (Seen, LineState for the edges below)."""
        scale = float(spp) ** 0.5   # undo Mitsuba's 1/sqrt(spp) scaling: one-pixel differentials
        o, d = mi.Point3f(ray.o), mi.Vector3f(ray.d)
        ox, oy = (ray.o_x - o) * scale, (ray.o_y - o) * scale
        dx, dy = (ray.d_x - d) * scale, (ray.d_y - d) * scale
        angle = dr.norm(dx)
        base = mi.Ray3f(o, d)
        q = scene.ray_intersect(base, ray_flags=self.flags, coherent=True, active=active)

        def aux(a, b):
            return mi.Ray3f(o + a * ox + b * oy, dr.normalize(d + a * dx + b * dy))

        seen = self._detect(scene, sampler, q, aux, lambda t: angle * t, active)
        return seen, LineState(D=dr.select(q.is_valid(), q.t, dr.inf), alive=mi.Bool(True), angle=angle)

    def edge(self, scene, sampler, state: LineState, si, bs, ray: mi.Ray3f, pi: mi.PreliminaryIntersection3f,
             index, active: mi.Bool):
        """The edge `ray` (leaving vertex si by the sample bs, reaching pi) with index `index`:
        (Seen, LineState after it)."""
        alive = state.alive & ~mi.has_flag(bs.sampled_type, mi.BSDFFlags.Diffuse)
        go = active & alive & (index < self.s.depth)
        D0 = state.D
        q = pi.compute_surface_interaction(ray, ray_flags=self.flags, active=go)
        d, n = mi.Vector3f(ray.d), mi.Vector3f(si.n)
        u, v = mi.coordinate_system(d)
        cos = dr.dot(d, n)
        flat = dr.abs(cos) > 1e-3
        side = dr.sign(cos)

        def aux(a, b):
            offset = state.angle * (a * u + b * v)
            o = si.p + D0 * offset
            # onto the vertex's tangent plane along d (where the mirrored camera's rays meet it)
            o = dr.select(flat, o - d * (dr.dot(o - si.p, n) / dr.select(flat, cos, 1.0)), o)
            o = o + n * side * (1.0 + dr.max(dr.abs(o))) * mi.math.RayEpsilon
            return mi.Ray3f(o, dr.normalize(d + offset))

        seen = self._detect(scene, sampler, q, aux, lambda t: state.angle * (D0 + t), go)
        # lanes that do not take this edge (halted at a stylized vertex, ended) keep their state
        after = LineState(D=dr.select(active, D0 + dr.select(pi.is_valid(), pi.t, dr.inf), D0),
                          alive=dr.select(active, alive, state.alive), angle=state.angle)
        return seen, after

    def _pair(self, a, b, radius_at, active):
        """Does a line separate the hits a and b? (fires, the pair's point, its distance)"""
        s = self.s
        a_valid, b_valid = a.is_valid(), b.is_valid()
        both = active & a_valid & b_valid
        fire = mi.Bool(False)
        if "silhouette" in s.tests:
            fire |= active & (a_valid != b_valid)
        if "boundary" in s.tests:
            fire |= both & (a.shape != b.shape)
        if "crease" in s.tests:
            fire |= both & (1.0 - dr.abs(dr.dot(a.n, b.n)) > s.crease)
        if "albedo" in s.tests:
            lum_a = mi.luminance(a.bsdf().eval_diffuse_reflectance(a, both))
            lum_b = mi.luminance(b.bsdf().eval_diffuse_reflectance(b, both))
            fire |= both & (dr.abs(lum_a - lum_b) > s.albedo)
        # the pair's point: the nearer of its two hits (an occluder's outline is drawn over what is behind)
        use_b = b_valid & (~a_valid | (b.t < a.t))
        t = dr.select(use_b, b.t, a.t)
        if "depth" in s.tests:
            gap = dr.maximum(dr.abs(dr.dot(a.n, b.p - a.p)), dr.abs(dr.dot(b.n, a.p - b.p)))
            fire |= both & (gap > s.slope * 0.5 * s.width * radius_at(t))
        fire &= self._draws(a) | self._draws(b)
        return fire, dr.select(use_b, b.p, a.p), t

    def _detect(self, scene, sampler, q, aux, radius_at, active) -> Seen:
        """absorb: N auxiliary rays `aux(a, b)` against the base hit q; expectation: k pairs of auxiliary
        rays against each other. (a, b) uniform in the disc of radius width/2 pixels; `radius_at(t)`: the
        cone's radius per pixel at distance t along the edge (for the depth test)."""
        s = self.s
        half = 0.5 * s.width
        pairs = s.mode == "expectation"

        def hit(smp):
            uv = mi.warp.square_to_uniform_disk(smp.next_2d(active)) * half
            return scene.ray_intersect(aux(uv.x, uv.y), ray_flags=self.flags, coherent=False, active=active)

        def body(j, smp, fired, best_t, best_p):
            fire, p, t = self._pair(hit(smp) if pairs else q, hit(smp), radius_at, active)
            better = fire & (t < best_t)
            return j + 1, smp, fired | fire, dr.select(better, t, best_t), dr.select(better, p, best_p)

        count = s.k if pairs else s.samples
        state = (mi.UInt32(0), sampler, mi.Bool(False), mi.Float(dr.inf), mi.Point3f(0.0))
        # lanes that test nothing (past line_depth, after a diffuse vertex, ended) leave the loop at once
        _, _, fired, _, point = dr.while_loop(state, lambda j, *rest: active & (j < count), body,
                                              label="styletrace lines")
        return Seen(fired=fired, color=self.color(point))


__all__ = ["LineSettings", "LineState", "Lines", "Seen", "TESTS", "DEFAULT_TESTS", "MODES"]
