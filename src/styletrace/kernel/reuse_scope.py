"""What one reuse render reads, and which style slot each lane draws for.

`Scope` holds the integrator's public per-render state as its RenderContext bound it (targets,
emitter sampler, camera forward vector, settings) with the render's options; the helpers below read
the targets' style slots: the children a vertex of a level draws (n, or n0 then n_max of an adaptive
count), its slot per lane, and g of that slot.
"""
from __future__ import annotations

from dataclasses import dataclass

from styletrace.gate import dr, mi
from styletrace.kernel.scene_graph import any_ptr


@dataclass(frozen=True)
class Scope:
    """One reuse render: the integrator (its public seams `styled_mask` and `stylized`), the scene,
    what the integrator's RenderContext set for it, the pooled samples' weights ('balance',
    'pairwise', 'own') and `keep`, a dict receiving the first batch's pools (None for other
    batches)."""
    integ: object
    scene: mi.Scene
    settings: object
    targets: tuple
    emitters: object
    view: object
    weights: str
    keep: dict | None = None

    @classmethod
    def of(cls, integ, scene: mi.Scene, weights: str, keep: dict | None) -> "Scope":
        """The Scope of a render of `scene` by `integ`, inside its RenderContext.

        Args:
            integ: the `stylized` integrator, bound to the scene. scene: the scene rendered.
            weights: the pooled samples' weights ('balance', 'pairwise', 'own').
            keep: a dict receiving the first batch's pools, or None.

        Returns:
            The Scope.
        """
        return cls(
            integ,
            scene,
            integ.settings,
            tuple(integ.targets),
            integ.emitters,
            integ.view,
            weights,
            keep,
        )


@dataclass(frozen=True)
class Slots:
    """Per lane: its target (style slot index, -1 where none), its children count m (n0 of an
    adaptive count), and whether it may pool (it draws children and its BSDF has no delta or
    null part)."""
    target: mi.Int32
    m: mi.UInt32
    pool: mi.Bool


def most(n) -> int:
    """The most children a count draws: n_max of an adaptive n0:n_max, else n.

    Args:
        n: a children count: an int, or an adaptive count (with `n_max`).

    Returns:
        int.
    """
    return int(getattr(n, "n_max", n))


def children_per_lane(targets, level: int = 0) -> int:
    """M, the children stored per vertex of `level`: the largest count of a style slot that draws
    children (n_max for an adaptive count n0:n_max); 1 where none draws.

    Args:
        targets: the render's style targets. level: the stylized level (0: the first hit).

    Returns:
        int.
    """
    return max([most(t.slot.n(level)) for t in targets if not t.slot.style.closed_form] or [1])


def first_round(targets, level: int = 0) -> int:
    """The most children any vertex of `level` draws before the refinement round (n0 of an
    adaptive count); 1 where none draws.

    Args:
        targets: the render's style targets. level: the stylized level (0: the first hit).

    Returns:
        int.
    """
    return max([int(t.slot.n(level)) for t in targets if not t.slot.style.closed_form] or [1])


def refined(targets) -> list[int]:
    """The targets whose first-level count is adaptive (n0:n_max): those the refinement
    round serves.

    Args:
        targets: the render's style targets.

    Returns:
        Their indices in `targets`.
    """
    return [i for i, t in enumerate(targets) if most(t.slot.n(0)) > int(t.slot.n(0))]


def slots(scope: Scope, si, hit, bsdf, level: int) -> Slots:
    """The `Slots` of the lanes at vertices `si` at a stylized level.

    Args:
        scope: the render's Scope. si: the vertices (mi.SurfaceInteraction3f).
        hit: the lanes at a surface (mi.Bool). bsdf: their BSDFs (mi.BSDFPtr).
        level: the stylized level whose counts apply.

    Returns:
        Slots: target index (-1: none), children count m (n0 of an adaptive count), may pool.
    """
    styled = scope.integ.styled_mask(si) if len(scope.targets) > 1 else mi.Bool(False)
    target, m = mi.Int32(-1), mi.UInt32(0)
    for i, t in enumerate(scope.targets):
        here = hit & (any_ptr(si.bsdf(), t.bsdfs, mi.BSDFPtr) if t.bsdfs else ~styled)
        target = dr.select(here, i, target)
        m = dr.select(here, 0 if t.slot.style.closed_form else int(t.slot.n(level)), m)
    flags = bsdf.flags()
    pool = (
        (m > 0) & ~mi.has_flag(flags, mi.BSDFFlags.Delta) & ~mi.has_flag(flags, mi.BSDFFlags.Null)
    )
    return Slots(target, m, pool)


def styled_value(scope: Scope, target, x, v, fallback):
    """g of each lane's target applied to x (closed-form styles to nothing), `fallback` where
    no target.

    Args:
        scope: the render's Scope. target: each lane's target index (mi.Int32, -1: none).
        x: the argument of g (mi.Spectrum). v: the lanes' style Vertex.
        fallback: the value where no target applies (mi.Spectrum or a float).

    Returns:
        mi.Spectrum.
    """
    value = mi.Spectrum(fallback)
    for i, t in enumerate(scope.targets):
        style = t.slot.style
        g = style.apply(mi.Color3f(0.0), v) if style.closed_form else style.apply(x, v)
        value = dr.select(target == i, g, value)
    return value
