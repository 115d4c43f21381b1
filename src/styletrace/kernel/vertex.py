"""What the walks share at one vertex: the vertex itself as the tree passes it on (`Site`), its
emission, the environment past an escaped ray, the power heuristic, Mitsuba's depth limit, and the
split of a BSDF with a null-scattering part (the opaque part a stylized vertex stands for, and the
probability of sampling it)."""
from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from styletrace.gate import dr, mi


@dataclass
class Site:
    """A stylized vertex: its preliminary and full intersection, the ray that reached it, its depth,
    the medium on the side that ray came from (None: vacuum, or a scene without media), and the
    volume.Collision of lanes whose vertex is in that medium instead (None: none can be; their si
    is then `volume.collision_site`'s)."""
    pi: mi.PreliminaryIntersection3f
    si: mi.SurfaceInteraction3f
    ray: mi.Ray3f
    depth: Any
    medium: Any = None
    collision: Any = None


def mis_power(pdf_a: mi.Float, pdf_b: mi.Float) -> mi.Float:
    """Power heuristic weight a^2 / (a^2 + b^2) of strategy a against b, finite for every input:
    written 1 / (1 + (b/a)^2), as squaring first overflows float32 (docs/design/path_kernel.md);
    0 where a vanishes, 1 where only a is infinite, 1/2 where both are.

    Args:
        pdf_a, pdf_b: the two strategies' densities (mi.Float), in the same measure.

    Returns:
        mi.Float, detached.
    """
    r = pdf_b / pdf_a
    w = dr.rcp(dr.fma(r, r, 1.0))
    w = dr.select(dr.isnan(r), 0.5, w)
    return dr.detach(dr.select(pdf_a > 0, w, 0.0))


def depth_limit(max_depth: int) -> int:
    """Mitsuba's depth limit as an unsigned bound.

    Args:
        max_depth: the `max_depth` setting (negative: unbounded).

    Returns:
        max_depth, or 2^32 - 1 where it is negative.
    """
    return 0xFFFFFFFF if max_depth < 0 else max_depth


def environment(scene: mi.Scene, si: mi.SurfaceInteraction3f, active: mi.Bool) -> mi.Spectrum:
    """Radiance the environment sends along an escaped ray (zero where there is none).

    Args:
        scene: the scene. si: the ray's interaction (invalid where it escaped).
        active: the lanes asked (mi.Bool); those whose si is valid get 0.

    Returns:
        mi.Spectrum.
    """
    ds = mi.DirectionSample3f(scene, si=si, ref=dr.zeros(mi.Interaction3f))
    return ds.emitter.eval(si, active & ~si.is_valid())


def emission(scene: mi.Scene, si: mi.SurfaceInteraction3f, active: mi.Bool) -> mi.Spectrum:
    """Radiance emitted at si towards si.wi (or by the environment where si escaped).

    Args:
        scene: the scene. si: the vertex. active: the lanes asked (mi.Bool).

    Returns:
        mi.Spectrum.
    """
    return si.emitter(scene).eval(si, active)


def null_split(si: mi.SurfaceInteraction3f, bsdf, u: mi.Float, active: mi.Bool):
    """Where a surface lets light through unscattered (a `mask`'s transparent part, a `null` BSDF),
    choose between passing through and scattering: with T = `eval_null_transmission` the ray passes
    with probability p = mean(T) and weight T/p, else scatters with weight (1 - T)/(1 - p) (both 1
    for grey T): the choice Mitsuba's BSDFs make, sampling their null component with probability T.

    Args:
        si, bsdf: the vertex and its BSDF. u: a uniform sample (mi.Float).
        active: the lanes with a null part (mi.Bool).

    Returns:
        (passes mi.Bool, pass weight mi.Spectrum, stay weight mi.Spectrum).
    """
    T = bsdf.eval_null_transmission(si, active)
    p = dr.clip(dr.mean(T), 0.0, 1.0)
    passes = active & (u < p)
    w_pass = dr.select(p > 0, T / p, 0.0)
    w_stay = dr.select(p < 1, (1.0 - T) / (1.0 - p), 0.0)
    return passes, w_pass, w_stay


def opaque_part(si: mi.SurfaceInteraction3f, bsdf, active: mi.Bool) -> mi.Spectrum:
    """1 / (1 - T): the factor that turns a BSDF's scattering into that of its opaque part alone
    (the part a stylized vertex stands for, see `first_scattering`); 0 where nothing scatters.

    Args:
        si, bsdf: the vertex and its BSDF. active: the lanes asked (mi.Bool).

    Returns:
        mi.Spectrum.
    """
    keep = 1.0 - bsdf.eval_null_transmission(si, active)
    return dr.select(keep > 0, dr.rcp(keep), 0.0)


def opaque_share(si: mi.SurfaceInteraction3f, bsdf, active: mi.Bool) -> mi.Float:
    """1 - p, p = mean(T) as in `null_split`: the probability with which Mitsuba's BSDFs sample
    their scattering (non-null) part. They sample it where their first uniform `sample1` is below
    1 - p (a `mask` its nested BSDF where sample1 < opacity, a `thindielectric` its reflection where
    sample1 <= R), and pass sample1 / (1 - p) on to that part. So a stylized vertex scales its
    sample1 into [0, 1 - p): its children sample the opaque part alone, as the opaque surface itself
    would, with weight f/pdf of that part, and none is spent on the null part (`walk`, `bounce`).

    Args:
        si, bsdf: the vertex and its BSDF. active: the lanes asked (mi.Bool).

    Returns:
        mi.Float.
    """
    T = bsdf.eval_null_transmission(si, active)
    return 1.0 - dr.clip(dr.mean(T), 0.0, 1.0)
