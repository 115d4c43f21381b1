"""Spatial emitter selection: per shading point, each emitter's probability follows an importance
built from its power, its distance and which way it shines (`emitter_sampling spatial`). Design
and why it is unbiased: docs/design/spatial_emitter_selection.md.

A point x with normal n (zero in a medium) gives emitter k the importance

    FINITE:       I_k  E(x) R(x) / max(d^2, r^2, D2_MIN)
    ENVIRONMENT:  pi L_mean
    DIRECTIONAL:  E  R(x)

with I_k the peak intensity (`emitter_bounds`), d the distance from x to its bounding sphere's
centre, r the sphere's radius, E the emitter-side bound cos(max(0, theta_w - theta_b - cone))
(theta_w: the angle between the cone's axis and the direction to x, theta_b: the half-angle the
sphere subtends at x), 0 where theta_w - theta_b >= cone + spread (the emitter provably cannot
light x) and at least FLOOR elsewhere, and R the receiver-side bound of |cos| between n and any
direction to the sphere, at least FLOOR (1 without a normal). Every emitter times its
`sampling_weight`. The probability mixes, with weight DEFENSIVE, one proportional to
`sampling_weight` over the emitters that can light x, so none of those gets a small one by a bad
estimate. Both walks over the emitters (sampling, density) compute every importance with the same
operations, so `pmf` returns exactly the probability `sample` reported.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

from styletrace.gate import dr, mi
from styletrace.kernel.emitter_bounds import ENVIRONMENT, FINITE, EmitterBounds

#: share of the probability spread by `sampling_weight` over the emitters that can light the point,
#: against importances that occlusion or a poor intensity estimate make wrong; chosen on the
#: corridor of benchmarks/emitter_sampling.py (`--tune`; none of its table's scenes): MSE 6.6e-4
#: at 0, 6.4e-4 at 0.05, 6.6e-4 at 0.1, 7.5e-4 at 0.2, 1.0e-3 at 0.4 (uniform selection 8.7e-3)
DEFENSIVE = 0.05
#: least value of either cosine bound where the emitter can light the point: shading normals and
#: rounding make a light in the point's tangent plane (or at its cone's edge) still count
FLOOR = 1e-2
#: least squared distance, as a share of the squared scene radius (a point on a point light)
D2_SHARE = 1e-8
#: most emitters whose walks are unrolled: their parameters become constants of the kernel, which
#: picked 2^20 lanes among the room's 32 lamps 7x faster than a loop gathering them one by one
#: (0.05 s against 0.36 s). The compile grows with it (the room with 100 lights: 2.5 s, and a
#: render at 2.4x the CPU time of uniform selection; as a loop of packet gathers, 4x at 70)
UNROLL = 128
#: the last float below 1, the most a reused sample may be
ONE_MINUS_EPSILON = 1.0 - 2.0**-24


def _sub_clamped(cos_a, sin_a, cos_b, sin_b):
    """cos and sin of max(0, a - b) for angles a, b in [0, pi] given by their cos and sin."""
    later = cos_a < cos_b  # a > b
    return (dr.select(later, cos_a * cos_b + sin_a * sin_b, 1.0),
            dr.select(later, sin_a * cos_b - cos_a * sin_b, 0.0))


@dataclass
class Emitter:
    """One emitter's parameters as `importance` reads them: Python numbers (the walk unrolled) or
    Dr.Jit arrays gathered by index (the walk a loop). kind: FINITE, ENVIRONMENT or DIRECTIONAL;
    center, axis: 3-vectors; cos_cone, sin_cone: the cone's half-angle; cos_reach: the cosine of
    cone + spread (-2 where that reaches pi); intensity, weight: times `sampling_weight`, and it."""
    kind: Any
    center: Any
    axis: Any
    radius: Any
    radius2: Any
    cos_cone: Any
    sin_cone: Any
    cos_reach: Any
    intensity: Any
    weight: Any


@dataclass
class Point:
    """A lane's shading point as `importance` reads it: p, the unit normal n (zero in a medium)
    and whether it has one."""
    p: mi.Point3f
    n: mi.Vector3f
    has_n: mi.Bool

    @staticmethod
    def of(it) -> Point:
        """The shading points of an interaction.

        Args:
            it: an mi.Interaction3f or mi.SurfaceInteraction3f (its p and geometric normal n).

        Returns:
            Point.
        """
        p, n = mi.Point3f(it.p), mi.Vector3f(it.n)
        nn = dr.squared_norm(n)
        has_n = nn > 0.0
        return Point(p, n * dr.rsqrt(dr.select(has_n, nn, 1.0)), has_n)


def finite_importance(e: Emitter, x: Point, d2_min: float):
    """A FINITE emitter's importance at x and its defensive weight (module docstring).

    Args:
        e: the emitter's parameters. x: the shading points. d2_min: the least squared distance.

    Returns:
        (importance mi.Float, 0 where the emitter provably cannot light x; `sampling_weight` where
        it can, else 0).
    """
    v = x.p - mi.Point3f(e.center)  # from the emitter towards the point
    d2 = dr.squared_norm(v)
    inside = d2 <= e.radius2
    inv_d = dr.rsqrt(dr.maximum(d2, d2_min))
    # the bounding sphere's half-angle seen from x (pi inside it)
    sin_b = dr.minimum(e.radius * inv_d, 1.0)
    cos_b = dr.safe_sqrt(1.0 - sin_b * sin_b)
    # emitter side: the direction to x against the cone, less the sphere's half-angle
    cos_w = dr.clip(dr.dot(mi.Vector3f(e.axis), v) * inv_d, -1.0, 1.0)
    cos_wb, sin_wb = _sub_clamped(cos_w, dr.safe_sqrt(1.0 - cos_w * cos_w), cos_b, sin_b)
    reach = inside | (cos_wb > e.cos_reach)
    cos_e, _ = _sub_clamped(cos_wb, sin_wb, e.cos_cone, e.sin_cone)
    emit = dr.select(inside, 1.0, dr.maximum(cos_e, FLOOR))
    # receiver side: |cos| between n and the closest direction to the sphere
    cos_i = dr.minimum(dr.abs(dr.dot(x.n, v)) * inv_d, 1.0)
    cos_ib, _ = _sub_clamped(cos_i, dr.safe_sqrt(1.0 - cos_i * cos_i), cos_b, sin_b)
    receive = dr.select(x.has_n & ~inside, dr.maximum(cos_ib, FLOOR), 1.0)
    value = e.intensity * emit * receive / dr.maximum(dr.maximum(d2, e.radius2), d2_min)
    return dr.select(reach, value, 0.0), dr.select(reach, e.weight, 0.0)


def directional_importance(e: Emitter, x: Point):
    """A DIRECTIONAL emitter's importance at x and its defensive weight.

    Args:
        e: the emitter's parameters (axis: the direction its light travels). x: the shading points.

    Returns:
        (its irradiance times max(|cos(n, axis)|, FLOOR), 1 without a normal; `sampling_weight`).
    """
    cos_s = dr.minimum(dr.abs(dr.dot(x.n, mi.Vector3f(e.axis))), 1.0)
    return e.intensity * dr.select(x.has_n, dr.maximum(cos_s, FLOOR), 1.0), mi.Float(e.weight)


def importance(e: Emitter, x: Point, d2_min: float):
    """Emitter e's importance at the points x, and its defensive weight.

    Args:
        e: the emitter's parameters (numbers or gathered arrays).
        x: the shading points.
        d2_min: the least squared distance.

    Returns:
        (importance mi.Float >= 0, `sampling_weight` where e can light x else 0 (mi.Float)).
    """
    if isinstance(e.kind, int):  # unrolled: the kind is known
        if e.kind == FINITE:
            return finite_importance(e, x, d2_min)
        if e.kind == ENVIRONMENT:
            return mi.Float(e.intensity), mi.Float(e.weight)
        return directional_importance(e, x)
    value_f, weight_f = finite_importance(e, x, d2_min)
    value_s, _ = directional_importance(e, x)
    value = dr.select(e.kind == FINITE, value_f,
                      dr.select(e.kind == ENVIRONMENT, e.intensity, value_s))
    return value, dr.select(e.kind == FINITE, weight_f, e.weight)


class SpatialSelection:
    """Selection probabilities that depend on the shading point (module docstring), over the
    emitters in the caller's order. Up to UNROLL emitters the walks over them are unrolled (their
    parameters become constants of the kernel); beyond, they are Dr.Jit loops gathering them.

    Args:
        bounds: each emitter's EmitterBounds, in selection order (at least one).
        weights: each emitter's `sampling_weight`, >= 0.
        scene_radius: the radius of the scene's bounding sphere, > 0.
    """

    def __init__(self, bounds: list[EmitterBounds], weights: list[float], scene_radius: float):
        self.count = len(bounds)
        self.d2_min = D2_SHARE * scene_radius * scene_radius
        self.emitters = []
        for b, w in zip(bounds, weights):
            clean = b.intensity if math.isfinite(b.intensity) and b.intensity > 0 else 0.0
            cone = min(b.cone, math.pi)
            # a reach of pi or more excludes no point: below every cosine
            reach = math.cos(b.cone + b.spread) if b.cone + b.spread < math.pi else -2.0
            self.emitters.append(Emitter(
                kind=b.kind, center=tuple(b.center), axis=tuple(b.axis), radius=b.radius,
                radius2=b.radius * b.radius, cos_cone=math.cos(cone), sin_cone=math.sin(cone),
                cos_reach=reach, intensity=w * clean, weight=float(w)))
        self.unrolled = self.count <= UNROLL
        if not self.unrolled:
            # one row of 16 floats per emitter, read as four packets of 4 (1.5x faster than
            # a gather per parameter)
            rows = []
            for e in self.emitters:
                rows += [*e.center, e.radius, *e.axis, e.radius2, e.cos_cone, e.sin_cone,
                         e.cos_reach, e.intensity, e.weight, float(e.kind), 0.0, 0.0]
            self.rows = mi.Float(rows)

    def emitter(self, k) -> Emitter:
        """Emitter k's parameters: the numbers (k an int), or gathered from `rows` (k a
        mi.UInt32)."""
        if isinstance(k, int):
            return self.emitters[k]
        q = [dr.gather(mi.Vector4f, self.rows, k * 4 + j) for j in range(4)]
        return Emitter(kind=mi.UInt32(q[3].y), center=mi.Point3f(q[0].x, q[0].y, q[0].z),
                       axis=mi.Vector3f(q[1].x, q[1].y, q[1].z), radius=q[0].w, radius2=q[1].w,
                       cos_cone=q[2].x, sin_cone=q[2].y, cos_reach=q[2].z, intensity=q[2].w,
                       weight=q[3].x)

    def walk(self, x: Point, state: tuple, step, active: mi.Bool, label: str) -> tuple:
        """Runs `step(k, value, weight, *state) -> state` over the emitters in order, value and
        weight being emitter k's `importance` at x: unrolled (on every lane: the caller branches),
        or a Dr.Jit loop on the active lanes.

        Args:
            x: the shading points. state: the carried values (Dr.Jit arrays). step: the body.
            active: the lanes that walk (the loop's). label: the loop's name.

        Returns:
            The final state.
        """
        if self.unrolled:
            for k in range(self.count):
                state = step(mi.UInt32(k), *self.value_at(k, x), *state)
            return state

        def body(k, *carried):
            return (k + 1, *step(k, *self.value_at(k, x), *carried))

        out = dr.while_loop((mi.UInt32(0), *state), lambda k, *_: active & (k < self.count),
                            body, label=label)
        return out[1:]

    def value_at(self, k, x: Point):
        """Emitter k's importance and defensive weight at x (`importance`)."""
        return importance(self.emitter(k), x, self.d2_min)

    def branch(self, fn, args: tuple, types: tuple, active: mi.Bool, label: str) -> tuple:
        """fn(*args) on the active lanes, zeros on the others: unrolled walks in a branch of the
        kernel that packets without an active lane skip.

        Args:
            fn: returns a tuple of Dr.Jit arrays. args: its Dr.Jit arguments.
            types: the types of fn's results (the zeros'). active: the lanes (mi.Bool).
            label: the branch's name.

        Returns:
            fn's tuple.
        """
        if not self.unrolled:
            return fn(*args)
        width = dr.width(active)
        return dr.if_stmt(args, active, fn, lambda *_: tuple(dr.zeros(t, width) for t in types),
                          label=label)

    @staticmethod
    def _mixture(total, defensive):
        """The factors (a, b) of the unnormalised weight a importance + b defensive weight, and
        its sum a total + b defensive (module docstring)."""
        some = total > 0.0
        a = dr.select(some, (1.0 - DEFENSIVE) * defensive, 0.0)
        b = dr.select(some, DEFENSIVE * total, 1.0)
        return a, b, a * total + b * defensive

    def sample(self, it: mi.Interaction3f, u: mi.Float, active: mi.Bool):
        """Picks an emitter per lane.

        Args:
            it: the shading points (p, n). u: a uniform sample in [0, 1) (reused).
            active: the lanes that pick (mi.Bool).

        Returns:
            (index mi.UInt32 in selection order, the reused sample mi.Float in [0, 1), its
            probability mi.Float; 0 where no emitter can light the point or the lane is off).
        """
        active = mi.Bool(active)
        x = Point.of(it)
        width = dr.width(x.p)

        def pick(u):
            zf, zu = dr.zeros(mi.Float, width), dr.zeros(mi.UInt32, width)
            total, defensive = self.walk(
                x, (zf, mi.Float(zf)), lambda k, value, weight, t, w: (t + value, w + weight),
                active, "styletrace spatial emitter totals")
            a, b, norm = self._mixture(total, defensive)
            target = u * norm

            def step(k, value, weight, cum, index, low, chosen, last, low_last, chosen_last,
                     done):
                f = a * value + b * weight
                upper = cum + f
                some = f > 0.0
                hit = ~done & some & (target < upper)
                # rounding may leave target past the last sum: then the last emitter with some
                # weight is the pick
                return (upper, dr.select(hit, k, index), dr.select(hit, cum, low),
                        dr.select(hit, f, chosen), dr.select(some, k, last),
                        dr.select(some, cum, low_last), dr.select(some, f, chosen_last),
                        done | hit)

            state = (mi.Float(zf), zu, mi.Float(zf), mi.Float(zf), mi.UInt32(zu), mi.Float(zf),
                     mi.Float(zf), dr.zeros(mi.Bool, width))
            _, index, low, chosen, last, low_last, chosen_last, done = self.walk(
                x, state, step, active, "styletrace spatial emitter pick")
            index = dr.select(done, index, last)
            low, chosen = dr.select(done, low, low_last), dr.select(done, chosen, chosen_last)
            ok = chosen > 0.0
            reused = dr.clip((target - low) / dr.select(ok, chosen, 1.0), 0.0, ONE_MINUS_EPSILON)
            pmf = dr.select(ok, chosen / dr.select(ok, norm, 1.0), 0.0)
            return index, dr.select(ok, reused, 0.0), pmf

        index, reused, pmf = self.branch(pick, (mi.Float(u),), (mi.UInt32, mi.Float, mi.Float),
                                         active, "styletrace spatial emitter pick")
        ok = active & (pmf > 0.0)
        return dr.select(ok, index, 0), dr.select(ok, reused, 0.0), dr.select(ok, pmf, 0.0)

    def pmf(self, it: mi.Interaction3f, index: mi.UInt32, active: mi.Bool) -> mi.Float:
        """The probability `sample` gives emitter `index` at the points of `it`.

        Args:
            it: the shading points (p, n). index: the emitters, in selection order (mi.UInt32).
            active: the lanes asked (mi.Bool).

        Returns:
            mi.Float, 0 on inactive lanes.
        """
        active = mi.Bool(active)
        x = Point.of(it)

        def density(index):
            zero = dr.zeros(mi.Float, dr.width(x.p))

            def step(k, value, weight, total, defensive, value_k, weight_k):
                mine = k == index
                return (total + value, defensive + weight, dr.select(mine, value, value_k),
                        dr.select(mine, weight, weight_k))

            total, defensive, value, weight = self.walk(
                x, (zero, mi.Float(zero), mi.Float(zero), mi.Float(zero)), step, active,
                "styletrace spatial emitter density")
            a, b, norm = self._mixture(total, defensive)
            f = a * value + b * weight
            ok = f > 0.0
            return (dr.select(ok, f / dr.select(ok, norm, 1.0), 0.0),)

        (pmf,) = self.branch(density, (mi.UInt32(index),), (mi.Float,), active,
                             "styletrace spatial emitter density")
        return dr.select(active, pmf, 0.0)
