"""Checks of the Python API's call arguments and of loaded scenes, before anything renders.

    check_render_args(spp=16, seed=0, integrator=None)  # UsageError: the argument, what is allowed
    check_scene(scene, "scene file 'x.xml'")  # SceneError: no sensor, a spectrum RGB cannot render

`api.render`, `api.passes` and `api.load_scene` call these first, so a bad argument fails with one
line instead of a TypeError deep in Mitsuba or a silently different image. Needs Mitsuba (a variant
set).
"""
from __future__ import annotations

import functools
import numbers
from typing import Any

from styletrace.errors import SceneError, UsageError
from styletrace.gate import mi

#: Seeds are 32-bit: Mitsuba's samplers take the seed modulo 2^32, so 0 and 2^32 would give one
#: image.
SEED_MAX = 2 ** 32 - 1
#: spp is a UInt32 sample count in Mitsuba's samplers.
SPP_MAX = 2 ** 32 - 1
#: Plugin classes whose spectra an RGB variant cannot evaluate: the first pass fails inside the
#: kernel.
UNRENDERABLE = {
    "BlackBodySpectrum": "a 'blackbody' spectrum needs a spectral variant; give the emitter an RGB "
    'radiance (<rgb name="radiance" value="..."/>) instead'
}


def whole(name: str, value: Any, low: int, high: int) -> int:
    """An int argument in [low, high]; bools, floats and strings are refused, not converted.

    Args:
        name: the argument's name, for the message; value: its value.
        low, high: the inclusive range.

    Returns:
        `value` as an int.

    Raises:
        UsageError: a value that is no integral number (or a bool), or outside [low, high].
    """
    if (isinstance(value, bool) or not isinstance(value, numbers.Integral)
            or not low <= value <= high):
        raise UsageError(f"bad value {value!r} for {name}: expected an integer in [{low}, {high}]")
    return int(value)


def check_integrator(integrator: Any) -> None:
    """Refuse an `integrator=` argument that is no Mitsuba integrator.

    Args:
        integrator: None or an mi.Integrator (`styletrace.make_integrator(...)`).

    Raises:
        UsageError: anything else (a style name, say: the message points to style=...).
    """
    if integrator is not None and not isinstance(integrator, mi.Integrator):
        raise UsageError(
            f"bad value {integrator!r} for integrator: expected None or an mi.Integrator such as "
            f"styletrace.make_integrator(...); choose a style with style=..."
        )


def check_render_args(spp: Any, seed: Any, integrator: Any = None) -> None:
    """Check the arguments of `render` / `passes` that do not need the scene.

    Args:
        spp: camera samples per pixel, an int in [1, SPP_MAX].
        seed: an int in [0, SEED_MAX]; integrator: None or an mi.Integrator.

    Raises:
        UsageError: the first argument out of range or of the wrong type.
    """
    whole("spp", spp, 1, SPP_MAX)
    whole("seed", seed, 0, SEED_MAX)
    check_integrator(integrator)


def check_passes_args(scene: Any, integrator: Any, spp: Any, seed: Any) -> None:
    """Check the arguments of `passes`: a renderable scene as well, and its feature lines.

    Args:
        scene: the mi.Scene to render (`check_scene`).
        integrator, spp, seed: as for `check_render_args`.

    Raises:
        UsageError: as `check_render_args`.
        SceneError: a scene that cannot be rendered, or lines it cannot draw (`line_objects`
            naming shapes it lacks, lifted lines deeper than 1 in participating media).
    """
    check_render_args(spp, seed, integrator)
    check_scene(scene, "the scene")
    from styletrace.kernel.integrator import (
        StylizedIntegrator,  # needs a variant set, as the plugins do
    )
    from styletrace.kernel.line_hooks import line_problem
    if isinstance(integrator, StylizedIntegrator) and integrator.settings.lines is not None:
        from styletrace.kernel.lines import Lines
        from styletrace.kernel.scene_graph import SceneGraph
        problem = line_problem(integrator.settings, SceneGraph(scene).has_media)
        if problem is not None:
            raise SceneError(problem)
        # line_objects names shapes of this scene (else refused)
        Lines(integrator.settings.lines, scene)
    if isinstance(integrator, StylizedIntegrator) and integrator.settings.light_groups:
        from styletrace.kernel.light_groups import check_scene as check_groups
        check_groups(scene, integrator.settings.light_groups)  # marks, media, styled objects


@functools.cache
def _collector() -> type:
    """The traversal callback class of `_objects`, one for the process (made on first use, when a
    variant is set). Design: docs/design/collection_during_traces.md."""

    class Collect(mi.TraversalCallback):
        def __init__(self, seen: dict[int, mi.Object]):
            super().__init__()
            self.seen = seen

        def put(self, name, value, *flags):
            if isinstance(value, mi.Object) and id(value) not in self.seen:
                self.seen[id(value)] = value
                _objects(value, self.seen)

    return Collect


def _objects(obj: mi.Object, seen: dict[int, mi.Object]) -> None:
    """Every Mitsuba object reachable from `obj` through traverse(), into `seen` (by id)."""
    try:
        obj.traverse(_collector()(seen))
    except Exception:  # a Python plugin without a traversal of its own: nothing below it to find
        pass


def scene_problem(scene: Any, origin: str) -> str | None:
    """Why a scene cannot be rendered; the message is returned, not raised, so that the caller
    drops its reference to the scene first (docs/design/refused_scenes.md).

    Args:
        scene: what was loaded (an mi.Scene, or another object).
        origin: how the message names it ("scene file 'x.xml'", "the scene dict", ...).

    Returns:
        One line: not a scene, no sensor, a spectrum the variant cannot render, styled BSDFs no
        style can apply to (`SceneGraph`); None for a renderable mi.Scene.
    """
    if not isinstance(scene, mi.Scene):
        kind = scene.class_name() if isinstance(scene, mi.Object) else type(scene).__name__
        return (
            f"{origin} is a {kind}, not a scene: expected a dict with 'type': 'scene' (or an XML "
            "<scene>) holding a sensor, shapes and emitters"
        )
    if not scene.sensors():
        return (f"{origin} has no sensor: add one (e.g. 'sensor': {{'type': 'perspective'}} or "
                f"<sensor type=\"perspective\"/>)")
    seen: dict[int, mi.Object] = {}
    _objects(scene, seen)
    names = {obj.class_name() for obj in seen.values()}
    seen.clear()
    for name in sorted(names & set(UNRENDERABLE)):
        return f"{origin} cannot be rendered in {mi.variant()}: {UNRENDERABLE[name]}"
    from styletrace.kernel.scene_graph import SceneGraph  # needs a variant set, as the plugins do
    try:
        SceneGraph(scene)  # styled BSDFs where no style can apply
    except SceneError as exc:
        return f"{origin}: {exc}"
    return None


def check_scene(scene: Any, origin: str) -> mi.Scene:
    """Check a scene the caller keeps anyway (so raising is safe: `scene_problem`).

    Args:
        scene: the scene to check; origin: how the message names it.

    Returns:
        `scene`, where it is a renderable mi.Scene.

    Raises:
        SceneError: `scene_problem`'s message, naming `origin`.
    """
    problem = scene_problem(scene, origin)
    if problem is not None:
        raise SceneError(problem)
    return scene


__all__ = ["check_render_args", "check_passes_args", "check_integrator", "check_scene",
           "scene_problem", "whole", "SEED_MAX"]
