"""Physically based feature lines on path edges (West 2021, "Physically-Based Feature Line
Rendering", ACM TOG 40(6) 246), detected on edges 0 .. `depth` - 1 of a camera path while every
vertex before the edge scattered non-diffusely; a line found absorbs the path (throughput x line
colour).

Detection: N auxiliary rays in a cone around the edge (camera edge: from the ray's differentials;
later edges: one pixel's beam), stencil points uniform in a disc of radius `width` / 2 pixels, each
tested against the base hit: silhouette, boundary, crease, albedo, depth (slope-aware). Stencil
rays pass pure `null` surfaces. `mode` expectation (LLaT): g = (1 - w) c + w L, w = E[m]^k,
estimated by k random pairs tested against each other. `objects`: the shapes that draw lines.
Design: docs/design/feature_lines.md.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from styletrace.config.choices import DEFAULT_TESTS, MODES, TESTS, LineSettings  # noqa: F401 (the kernel's names for them)
from styletrace.errors import SceneError
from styletrace.gate import dr, mi

#: at most this many `null` surfaces passed along one stencil ray (nested medium boundaries)
MAX_NULL_PASSES = 16

class LineState:
    """What a path carries for lines: accumulated length from the camera, whether no diffuse vertex
    was met yet, and one pixel's beam (from the camera ray's differentials): its angle and its width
    at the camera. A Dr.Jit struct.

    Args:
        D: the path length from the camera to the state's vertex (mi.Float; None: 0).
        alive: no diffuse vertex met yet (mi.Bool; None: True).
        angle, spread: the beam's angle per pixel (|d_x - d|) and its width at the camera (world
            units); mi.Float, None: 0.
    """
    DRJIT_STRUCT = {"D": mi.Float, "alive": mi.Bool, "angle": mi.Float, "spread": mi.Float}

    def __init__(self, D=None, alive=None, angle=None, spread=None):
        self.D = mi.Float(0.0) if D is None else D
        self.alive = mi.Bool(True) if alive is None else alive
        self.angle = mi.Float(0.0) if angle is None else angle
        self.spread = mi.Float(0.0) if spread is None else spread

    def width(self, t) -> mi.Float:
        """The beam's width per pixel at distance t past the state's vertex.

        Args:
            t: the distance along the next edge (mi.Float, world units).

        Returns:
            mi.Float, world units.
        """
        return self.spread + self.angle * (self.D + t)


@dataclass
class Edge:
    """A path edge that `Lines.edge` tests.

    Args:
        ray: the edge (mi.Ray3f), leaving its vertex.
        pi: where it reaches (mi.PreliminaryIntersection3f).
        index: the edge's index along the path (0: the camera ray; int or mi.UInt32).
    """

    ray: Any
    pi: Any
    index: Any


@dataclass
class Seen:
    fired: mi.Bool
    color: mi.Color3f


def object_shapes(scene: mi.Scene, objects) -> list:
    """The shapes named by `line_objects` (empty: all draw lines).

    Args:
        scene: the scene. objects: shape ids.

    Returns:
        list[mi.ShapePtr]; empty where `objects` is.

    Raises:
        SceneError: an id names no shape of the scene (in one line).
    """
    if not objects:
        return []
    by_id = {shape.id(): shape for shape in scene.shapes()}
    missing = [i for i in objects if i not in by_id]
    if missing:
        raise SceneError(f"bad value {missing[0]!r} in 'line_objects': the scene's shape ids are "
                         f"{', '.join(sorted(k for k in by_id if k)) or 'none'}")
    return [mi.ShapePtr(by_id[i]) for i in objects]


def on_shapes(si, shapes: list) -> mi.Bool:
    """Whether a hit is on one of `shapes` (every hit where `shapes` is empty).

    Args:
        si: the hits. shapes: `object_shapes`' pointers.

    Returns:
        mi.Bool.
    """
    if not shapes:
        return si.is_valid()
    mask = mi.Bool(False)
    for ptr in shapes:
        mask |= si.shape == ptr
    return si.is_valid() & mask


class Lines:
    """The line settings bound to one scene for one trace (shape pointers, the gradient's
    y range).

    Args:
        settings: the line settings (`lines` and the `line_*` settings). scene: the scene traced.
        see_through: the scene has a surface with a pure `null` BSDF
            (`SceneGraph.has_see_through`), so the stencil's rays must pass such surfaces (a loop
            per ray that other scenes do without).

    Raises:
        SceneError: `line_objects` names a shape the scene lacks.
    """

    def __init__(self, settings: LineSettings, scene: mi.Scene, see_through: bool = False):
        self.s = settings
        # positions, geometric normals and shapes are all the tests need; the albedo test
        # evaluates textures
        self.flags = mi.RayFlags.All if "albedo" in settings.tests else mi.RayFlags.Minimal
        self.shapes = object_shapes(scene, settings.objects)
        self.see_through = see_through
        if settings.gradient is not None:
            c0, c1, y0, y1 = settings.gradient
            box = scene.bbox()
            self.y0 = float(box.min.y) if y0 is None else y0
            self.y1 = float(box.max.y) if y1 is None else y1

    # ---- what a line looks like ---------------------------------------------------------------
    def color(self, p: mi.Point3f) -> mi.Color3f:
        """The line colour at p: `line_color`, or the gradient's colour at p's world y.

        Args:
            p: the line point (mi.Point3f).

        Returns:
            mi.Color3f.
        """
        if self.s.gradient is None:
            return mi.Color3f(*self.s.color)
        c0, c1 = mi.Color3f(*self.s.gradient[0]), mi.Color3f(*self.s.gradient[1])
        t = dr.clip((p.y - self.y0) / max(self.y1 - self.y0, 1e-12), 0.0, 1.0)
        return dr.lerp(c0, c1, t)

    def _draws(self, si) -> mi.Bool:
        return on_shapes(si, self.shapes)

    def trace(
        self, scene, ray: mi.Ray3f, active: mi.Bool, coherent: bool = False
    ) -> mi.SurfaceInteraction3f:
        """The first hit along `ray` that is not a pure `null` surface; its `t` is measured
        from ray.o.

        Args:
            scene: the scene. ray: the ray. active: the lanes that trace (mi.Bool).
            coherent: a hint to the intersection (camera rays are).

        Returns:
            mi.SurfaceInteraction3f.
        """
        if not self.see_through:
            return scene.ray_intersect(ray, ray_flags=self.flags, coherent=coherent, active=active)
        minimal = mi.RayFlags.Minimal
        pi = scene.ray_intersect_preliminary(ray, coherent=coherent, active=active)
        first = pi.compute_surface_interaction(ray, ray_flags=minimal, active=active)
        state = (
            pi,
            mi.Ray3f(ray),
            mi.Float(0.0),
            active & first.is_valid() & pure_null(first.bsdf().flags()),
            mi.UInt32(0),
        )

        def body(pi, ray, t, passing, n):
            si = pi.compute_surface_interaction(ray, ray_flags=minimal, active=passing)
            ahead = si.spawn_ray(ray.d)
            t = dr.select(passing, t + pi.t, t)
            ray = dr.select(passing, ahead, ray)
            pi = dr.select(
                passing, scene.ray_intersect_preliminary(ahead, coherent=False, active=passing), pi
            )
            nxt = pi.compute_surface_interaction(ray, ray_flags=minimal, active=passing)
            return pi, ray, t, passing & nxt.is_valid() & pure_null(nxt.bsdf().flags()), n + 1

        pi, ray, t, _, _ = dr.while_loop(
            state,
            lambda pi, ray, t, passing, n: passing & (n < MAX_NULL_PASSES),
            body,
            label="styletrace lines through null surfaces",
        )
        si = pi.compute_surface_interaction(ray, ray_flags=self.flags, active=active)
        si.t = dr.select(si.is_valid(), si.t + t, si.t)
        return si

    # ---- the edges -------------------------------------------------------------------------------
    def camera(self, scene, sampler, ray: mi.RayDifferential3f, spp: int, active: mi.Bool):
        """Edge 0, from the camera ray's differentials.

        Args:
            scene, sampler: the scene and the lanes' random stream.
            ray: the camera ray (mi.RayDifferential3f, its differentials scaled by Mitsuba).
            spp: the camera samples per pixel they were scaled for (undone: one-pixel
            differentials).
            active: the camera lanes (mi.Bool).

        Returns:
            (Seen, LineState for the edges below).
        """
        scale = float(spp) ** 0.5   # undo Mitsuba's 1/sqrt(spp) scaling: one-pixel differentials
        o, d = mi.Point3f(ray.o), mi.Vector3f(ray.d)
        ox, oy = (ray.o_x - o) * scale, (ray.o_y - o) * scale
        dx, dy = (ray.d_x - d) * scale, (ray.d_y - d) * scale
        angle, spread = dr.norm(dx), dr.norm(ox)
        base = mi.Ray3f(o, d)
        q = self.trace(scene, base, active, coherent=True)

        def aux(a, b):
            return mi.Ray3f(o + a * ox + b * oy, dr.normalize(d + a * dx + b * dy))

        seen = self._detect(scene, sampler, q, aux, lambda t: spread + angle * t, active)
        return seen, LineState(
            D=dr.select(q.is_valid(), q.t, dr.inf), alive=mi.Bool(True), angle=angle, spread=spread
        )

    def edge(
        self,
        scene,
        sampler,
        state: LineState,
        si,
        bs,
        edge: Edge,
        active: mi.Bool,
    ):
        """Lines on the edge `ray`, which leaves vertex si by the sample bs and reaches pi.

        Args:
            scene, sampler: the scene and the lanes' random stream.
            state: the LineState at si. si, bs: the vertex and its BSDF sample.
            edge: the edge's ray, its preliminary intersection and its index (0: camera).
            active: the lanes that take the edge (mi.Bool); the others keep their state.

        Returns:
            (Seen, LineState after the edge).
        """
        ray, pi = edge.ray, edge.pi
        alive = state.alive & ~mi.has_flag(bs.sampled_type, mi.BSDFFlags.Diffuse)
        go = active & alive & (edge.index < self.s.depth)
        D0 = state.D
        # the path's next vertex, unless it is a null surface, which the path passes after this test
        q = self.trace(scene, ray, go) if self.see_through else \
            pi.compute_surface_interaction(ray, ray_flags=self.flags, active=go)
        d, n = mi.Vector3f(ray.d), mi.Vector3f(si.n)
        u, v = mi.coordinate_system(d)
        cos = dr.dot(d, n)
        flat = dr.abs(cos) > 1e-3
        side = dr.sign(cos)

        def aux(a, b):
            lateral = a * u + b * v
            offset = state.angle * lateral
            o = si.p + state.width(0.0) * lateral
            # onto the vertex's tangent plane along d (where the mirrored camera's rays meet it)
            o = dr.select(flat, o - d * (dr.dot(o - si.p, n) / dr.select(flat, cos, 1.0)), o)
            o = o + n * side * (1.0 + dr.max(dr.abs(o))) * mi.math.RayEpsilon
            return mi.Ray3f(o, dr.normalize(d + offset))

        seen = self._detect(scene, sampler, q, aux, state.width, go)
        # lanes that do not take this edge (halted at a stylized vertex, ended) keep their state
        after = LineState(
            D=dr.select(active, D0 + dr.select(pi.is_valid(), pi.t, dr.inf), D0),
            alive=dr.select(active, alive, state.alive),
            angle=state.angle,
            spread=state.spread,
        )
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
        # the pair's point: the nearer of its two hits (an occluder's outline is drawn over what
        # is behind)
        use_b = b_valid & (~a_valid | (b.t < a.t))
        t = dr.select(use_b, b.t, a.t)
        if "depth" in s.tests:
            gap = dr.maximum(dr.abs(dr.dot(a.n, b.p - a.p)), dr.abs(dr.dot(b.n, a.p - b.p)))
            fire |= both & (gap > s.slope * 0.5 * s.width * radius_at(t))
        fire &= self._draws(a) | self._draws(b)
        return fire, dr.select(use_b, b.p, a.p), t

    def _detect(self, scene, sampler, q, aux, radius_at, active) -> Seen:
        """absorb: N auxiliary rays `aux(a, b)` against the base hit q; expectation: k pairs of
        auxiliary rays against each other. (a, b) uniform in the disc of radius width/2 pixels;
        `radius_at(t)`: the beam's width per pixel at distance t along the edge (for the
        depth test)."""
        s = self.s
        half = 0.5 * s.width
        pairs = s.mode == "expectation"

        def hit(smp):
            uv = mi.warp.square_to_uniform_disk(smp.next_2d(active)) * half
            return self.trace(scene, aux(uv.x, uv.y), active)

        def body(j, smp, fired, best_t, best_p):
            fire, p, t = self._pair(hit(smp) if pairs else q, hit(smp), radius_at, active)
            better = fire & (t < best_t)
            return (
                j + 1,
                smp,
                fired | fire,
                dr.select(better, t, best_t),
                dr.select(better, p, best_p),
            )

        count = s.k if pairs else s.samples
        state = (mi.UInt32(0), sampler, mi.Bool(False), mi.Float(dr.inf), mi.Point3f(0.0))
        # lanes that test nothing (past line_depth, after a diffuse vertex, ended) leave the loop
        # at once
        _, _, fired, _, point = dr.while_loop(state, lambda j, *rest: active & (j < count), body,
                                              label="styletrace lines")
        return Seen(fired=fired, color=self.color(point))


def pure_null(flags) -> Any:
    """BSDF flags of a surface that lets every ray through unchanged (a `null` BSDF): of the lobe
    flags (`BSDFFlags.All`) only Null, whatever the side flags; a mask or a BSDF with a null lobe
    besides others is not.

    Args:
        flags: BSDF flags, a Python int or a Dr.Jit UInt32.

    Returns:
        bool, or mi.Bool for an array.
    """
    null, lobes = int(mi.BSDFFlags.Null), int(mi.BSDFFlags.All)
    if isinstance(flags, int):
        return flags & lobes == null
    return (flags & lobes) == null


__all__ = ["LineSettings", "LineState", "Lines", "Seen", "TESTS", "DEFAULT_TESTS", "MODES"]
