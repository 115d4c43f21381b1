"""Light groups in the kernel: each emitter's group (`GroupTable`), a path's radiance split by the
group of the emitter each contribution ends on (`GroupTable.split`, in path.walk), and the groups'
estimators fed from the same children in one loop (`run_groups`).

    table = GroupTable(scene, settings.light_groups)   # per render (render_context.py)
    Lg = table.split(Lg, emitter, contribution, active)  # per contribution, in the walk
    values, carry = run_groups(estimators, draw, carry, uniform, active, like=mi.Color3f)

A group's estimator takes a child's value of its own group only: each group's estimate is that of
its own expectation, and where the estimators are unbiased the sum of the groups' estimates is
unbiased for the sum of the styled groups (Theorem 4.1's sum, its samples shared). Without groups
none of this is traced. Docs: docs/light_groups.md.
"""
from __future__ import annotations

from styletrace.config.light_groups import DEFAULT, group_mark
from styletrace.errors import SceneError, SettingsError
from styletrace.estimators.base import Context, Estimator
from styletrace.gate import dr, mi
from styletrace.kernel.emitter_sampler import emitter_id


def emitter_group(emitter) -> str:
    """The group an emitter's mark names: its own id's, else (an area light) its shape's.

    Args:
        emitter: an mi.Emitter.

    Returns:
        The group's name, '' where neither id carries a mark.
    """
    own = group_mark(emitter.id())
    shape = emitter.get_shape()
    return own or (group_mark(shape.id()) if shape is not None else "")


class GroupTable:
    """Each emitter's group index (0: `default`) by the registry id a lane's emitter pointer holds.

    Args:
        scene: the scene. groups: the parsed light groups (`default` first).

    Raises:
        SceneError: an emitter names a group not declared, or a declared group has no emitter.
    """

    def __init__(self, scene: mi.Scene, groups: tuple):
        self.names = [g.name for g in groups]
        index, used = {}, set()
        for e in scene.emitters():
            name = emitter_group(e) or DEFAULT
            if name not in self.names:
                raise SceneError(f"bad light group {name!r} of emitter {e.id()!r}: declared in "
                                 f"'light_groups' are {', '.join(self.names[1:])}")
            index[int(emitter_id(mi.EmitterPtr(e))[0])] = self.names.index(name)
            used.add(name)
        empty = [n for n in self.names[1:] if n not in used]
        if empty:
            raise SceneError(f"bad light group {empty[0]!r}: no emitter carries its mark "
                             f"'__lg_{empty[0]}' (in its id or its shape's)")
        table = [0] * (max(index, default=0) + 1)
        for i, k in index.items():
            table[i] = k
        self.by_id = mi.UInt32(table)
        env = scene.environment()
        #: the environment's group index (0 where there is none)
        self.environment = index.get(int(emitter_id(mi.EmitterPtr(env))[0]), 0) if env else 0

    @property
    def count(self) -> int:
        return len(self.names)

    def zeros(self) -> list:
        """One mi.Spectrum 0 per group."""
        return [mi.Spectrum(0.0) for _ in self.names]

    def index(self, emitter, active) -> mi.UInt32:
        """Each lane's emitter's group index (0 where there is none).

        Args:
            emitter: mi.EmitterPtr. active: the lanes asked (mi.Bool).

        Returns:
            mi.UInt32.
        """
        known = active & (emitter != None)  # noqa: E711  (a Dr.Jit pointer comparison)
        return dr.gather(mi.UInt32, self.by_id, emitter_id(emitter), known)

    def split(self, Lg: list, emitter, value, active) -> list:
        """`Lg` (one mi.Spectrum per group) with `value` added to the group of each lane's
        emitter.

        Args:
            Lg: the groups' radiance so far. emitter: mi.EmitterPtr the value ends on.
            value: the contribution (mi.Spectrum, 0 where it adds nothing). active: mi.Bool.

        Returns:
            The new list.
        """
        k = self.index(emitter, active)
        return [L + dr.select(k == i, value, 0.0) for i, L in enumerate(Lg)]


def check_scene(scene: mi.Scene, groups: tuple, graph=None) -> GroupTable | None:
    """Refuse what light groups do not support yet in a scene (participating media, objects with a
    `styled` BSDF) and marks that do not match the groups (`GroupTable`).

    Args:
        scene: the scene. groups: the parsed light groups (() : nothing to check).
        graph: its scene_graph.SceneGraph, if built already.

    Returns:
        The scene's GroupTable, or None without groups.

    Raises:
        SceneError: one line naming what is not supported or the bad mark.
    """
    if not groups:
        return None
    from styletrace.kernel.scene_graph import SceneGraph
    graph = SceneGraph(scene) if graph is None else graph
    if graph.has_media or graph.styled:
        what = "participating media" if graph.has_media else "objects with a 'styled' BSDF"
        raise SceneError(f"a scene with {what} and light_groups: not yet supported with light "
                         "groups; render it without light_groups")
    return GroupTable(scene, groups)


def _protocol(est):
    """(estimator, sample map, scale, offset) of a registry estimator (`Transformed`)."""
    inner = getattr(est, "inner", est)
    if not isinstance(inner, Estimator) or inner.uses_comb:
        raise SettingsError(f"bad estimator {est.name!r} with light_groups: not yet supported "
                            "with light groups (its children follow a comb or a loop of its own); "
                            "use direct, affine, series, ustat, naive or telescoping")
    return (inner, getattr(est, "sample", None), getattr(est, "scale", 1.0),
            getattr(est, "offset", 0.0))


def run_groups(estimators: list, draw, carry, uniform, active, like) -> tuple[list, object]:
    """One estimate per group and lane from shared children, in one loop: each iteration draws one
    child (one value per group) and hands each group's value to its estimator while it still
    wants one; the loop runs while any does (the kernel contract, docs/design/
    estimator_kernel_contract.md, with a sample per group).

    Args:
        estimators: the groups' estimators (`estimator_registry.make_estimator`'s), in the
            groups' order.
        draw: draw(carry) -> (list of one like-typed value per group, carry).
        carry, uniform, active, like: as `estimators.Estimator.run`.

    Returns:
        (list of the groups' estimates, 0 on inactive lanes before each's offset; carry).

    Raises:
        SettingsError: an estimator that draws by a comb or runs a loop of its own.
    """
    parts = [_protocol(e) for e in estimators]
    ctx, carry = Context.for_run(like, active, uniform, carry)
    states = []
    for inner, _, _, _ in parts:
        s, carry = inner.start(ctx, carry)
        states.append(s)

    def wants(states):
        w = parts[0][0].wants(ctx, states[0])
        for (inner, _, _, _), s in zip(parts[1:], states[1:]):
            w = w | inner.wants(ctx, s)
        return w

    def cond(states, carry, act):
        return wants(states) & act

    def body(states, carry, act):
        xs, carry = draw(carry)
        out = []
        for (inner, sample, _, _), s, x in zip(parts, states, xs):
            x = ctx.adopt(x if sample is None else sample(ctx.adopt(x)))
            s, carry = inner.feed(ctx, s, x, inner.wants(ctx, s), carry)
            out.append(s)
        return out, carry, act

    states, carry, _ = ctx.while_loop((states, carry, active), cond, body)
    values = []
    for (inner, _, scale, offset), s in zip(parts, states):
        v = ctx.finish(inner.value(ctx, s), active)
        values.append(v * scale + offset if (scale != 1.0 or offset != 0.0) else v)
    return values, carry


__all__ = ["GroupTable", "check_scene", "emitter_group", "run_groups"]
