"""The `stylized` integrator as Mitsuba builds it from a scene file or dict: `mi.render` pins `auto` values too.

    scene = mi.load_file("scene.xml")      # <integrator type="stylized"><string name="style" value="cel"/>...
    img = mi.render(scene)                 # cel thresholds from the scene's brightness, as `styletrace render`

The front ends pin a style's scene-relative `auto` values (`scene.defaults.resolve_defaults`) before Mitsuba's render
call. A user who loads a file and calls `mi.render` skips them, and got each style's unresolved fallback (cel
thresholds 0.5): the same file and seed drew another image. `from_properties`, the factory `runtime.init`
registers for `stylized`, gives such an integrator a `render` of its own (on the instance only, as the
reuse render is set: a Python `render` on the class changed how Ctrl-C reaches a render in progress) that
resolves against the scene once, caches the result for that scene, and hands the call to the resolved
integrator. That one is built from property values (`from_values`), so it has no such `render` and never
resolves again; the pilot itself traces the path kernel directly, never `mi.render`, so nothing recurses.
The pipeline never renders with this object: it builds its integrator from the values (`pipeline.resolve`).
"""
from __future__ import annotations

import weakref

from styletrace.gate import mi
from styletrace.kernel.integrator import StylizedIntegrator
from styletrace.scene.defaults import resolve_defaults


def scene_key(scene: mi.Scene) -> tuple:
    """What identifies the scene a resolution belongs to: the object and its film (a crop changes the pilot);
    no reference to the scene is kept (see `StylizedIntegrator.sample`)."""
    film = scene.sensors()[0].film() if scene.sensors() else None
    size = tuple(int(v) for v in film.crop_size()) if film is not None else ()
    offset = tuple(int(v) for v in film.crop_offset()) if film is not None else ()
    return id(scene), size, offset


class ResolvingRender:
    """The `render` a Mitsuba-built integrator gets (see the module doc). It holds its integrator weakly: a
    bound method would make a reference cycle, and garbage that only the collector frees changes what
    Dr.Jit traces (jit.no_collection says how); the resolved integrator it caches holds no scene object."""

    def __init__(self, integrator: StylizedIntegrator):
        self.owner = weakref.ref(integrator)
        self.resolved_for: tuple | None = None

    def __call__(self, scene, sensor=0, seed=0, spp=0, develop=True, evaluate=True):
        """`mi.render`'s call: render with the owner's values, `auto` values pinned on `scene` (cached)."""
        key = scene_key(scene)
        if self.resolved_for is None or self.resolved_for[0] != key:
            fresh = StylizedIntegrator.from_values(self.owner().values)
            self.resolved_for = (key, resolve_defaults(scene, fresh)[0])
        return self.resolved_for[1].render(scene, sensor, seed, spp, develop, evaluate)


def from_properties(props: mi.Properties) -> StylizedIntegrator:
    """A `stylized` integrator from Mitsuba properties whose `mi.render` resolves `auto` values (module doc)."""
    integrator = StylizedIntegrator(props)
    integrator.render = ResolvingRender(integrator)
    return integrator


__all__ = ["from_properties", "ResolvingRender", "scene_key"]
