"""What a loaded scene holds that the `stylized` integrator must know before it traces.

    graph = SceneGraph(scene)
    # [(StyledBSDF, [pointers an intersection reports for it], [its shapes' emitters])]
    graph.styled
    graph.has_null      # some surface BSDF has a Null component (a `mask`, a `null` BSDF, ...)
    # some surface BSDF is a pure `null` (feature lines pass it: lines.pure_null)
    graph.has_see_through
    graph.has_media     # some shape bounds a medium, or the sensor sits in one

Styled BSDFs are found inside wrappers and in shapegroups; ambiguous styling is refused.
Design: docs/design/scene_graph.md.
"""
from __future__ import annotations

from styletrace.errors import SceneError
from styletrace.gate import mi
from styletrace.kernel.lines import pure_null
from styletrace.kernel.styled_bsdf import StyledBSDF


class _Collect(mi.TraversalCallback):
    """Gathers the child objects a traversal hands over. One class for the module: a class made per
    call kept the objects it reached alive (docs/design/render_state.md)."""

    def __init__(self):
        super().__init__()
        self.found: list[mi.Object] = []

    def put(self, name, value, *flags):
        if isinstance(value, mi.Object):
            self.found.append(value)


def children(obj: mi.Object) -> list[mi.Object]:
    """The Mitsuba objects `obj` hands to its traversal callback (one level down).

    Args:
        obj: a Mitsuba object (a Python plugin without a traversal of its own hands none).

    Returns:
        list[mi.Object].
    """
    collect = _Collect()
    try:
        obj.traverse(collect)
    except Exception:  # a Python plugin without a traversal of its own: nothing below it to find
        pass
    found, collect.found = collect.found, []
    return found


def styled_inside(bsdf: mi.BSDF) -> list[StyledBSDF]:
    """The distinct styled BSDFs in `bsdf` itself or nested at any depth inside its wrappers.

    Args:
        bsdf: a shape's BSDF.

    Returns:
        list[StyledBSDF].

    Raises:
        SceneError: a styled BSDF holds another one (whose style would never apply).
    """
    found: dict[int, StyledBSDF] = {}
    stack, seen = [bsdf], set()
    while stack:
        obj = stack.pop()
        if id(obj) in seen:
            continue
        seen.add(id(obj))
        if isinstance(obj, StyledBSDF):
            found[id(obj)] = obj
            if styled_inside(obj.nested):
                raise SceneError(
                    f"a 'styled' BSDF ({obj.slot.style.describe()}) holds another 'styled' BSDF, "
                    "whose style would never apply: keep one 'styled' BSDF per surface"
                )
            continue  # its traversal forwards to the nested BSDF's parameters, checked above
        stack.extend(children(obj))
    return list(found.values())


def all_shapes(scene: mi.Scene) -> list[mi.Shape]:
    """Every shape of the scene with a surface, those inside shapegroups (seen through
    instances) too.

    Args:
        scene: a loaded scene.

    Returns:
        list[mi.Shape], each with a BSDF.
    """
    shapes: dict[int, mi.Shape] = {id(s): s for s in scene.shapes()}
    stack, seen = list(children(scene)), set()
    while stack:
        obj = stack.pop()
        if id(obj) in seen or not isinstance(obj, mi.Shape):
            continue
        seen.add(id(obj))
        shapes.setdefault(id(obj), obj)
        stack.extend(children(obj))  # a shapegroup hands over its shapes
    return [s for s in shapes.values() if s.bsdf() is not None]


def _name(shape: mi.Shape) -> str:
    return shape.id() or shape.class_name()


class SceneGraph:
    """What a loaded scene holds for the `stylized` integrator (module docstring).

    Args:
        scene: a loaded scene.

    Raises:
        SceneError: a shape emits light through a see-through BSDF, a surface holds two styled
            BSDFs, or a styled BSDF holds another.
    """
    def __init__(self, scene: mi.Scene):
        groups: dict[int, tuple] = {}
        self.has_null = False
        self.has_see_through = False   # some surface has a pure `null` BSDF (feature lines pass it)
        self.has_media = scene.sensors()[0].get_medium() is not None if scene.sensors() else False
        for shape in all_shapes(scene):
            bsdf = shape.bsdf()
            if mi.has_flag(bsdf.flags(), mi.BSDFFlags.Null):
                self.has_null = True
                self.has_see_through |= pure_null(bsdf.flags())
                if shape.emitter() is not None:  # see path.first_scattering for why
                    raise SceneError(
                        f"shape '{_name(shape)}' emits light through a see-through "
                        f"{bsdf.class_name()} BSDF, which 'stylized' does not support: give the "
                        "emitter an opaque BSDF"
                    )
            self.has_media |= (
                shape.interior_medium() is not None or shape.exterior_medium() is not None
            )
            styled = styled_inside(bsdf)
            if len(styled) > 1:
                raise SceneError(
                    f"shape '{_name(shape)}': its {bsdf.class_name()} BSDF holds {len(styled)} "
                    "'styled' BSDFs, but a surface takes one style: wrap the whole BSDF in one "
                    "'styled' instead"
                )
            if not styled:
                continue
            s = styled[0]
            _, pointers, emitters = groups.setdefault(id(s), (s, [s], []))
            if all(p is not bsdf for p in pointers):
                pointers.append(bsdf)
            if shape.emitter() is not None:
                emitters.append(shape.emitter())
        self.styled = list(groups.values())


def any_ptr(ptr, objects, ptr_type) -> mi.Bool:
    """Lanes whose pointer (BSDF, emitter, ...) is one of `objects`.

    Args:
        ptr: the lanes' pointers (mi.BSDFPtr, mi.EmitterPtr, ...).
        objects: Mitsuba objects. ptr_type: the pointer type they are compared as.

    Returns:
        mi.Bool.
    """
    mask = mi.Bool(False)
    for obj in objects:
        mask |= ptr == ptr_type(obj)
    return mask
