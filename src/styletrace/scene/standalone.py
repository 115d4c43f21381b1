"""The `stylized` integrator as Mitsuba builds it from a scene file or dict: `mi.render` pins
`auto` values too.

    scene = mi.load_file("scene.xml")  # <integrator type="stylized"><string name="style" .../>
    img = mi.render(scene)             # cel thresholds from the scene's brightness, as the CLI's

`from_properties`, the factory `scene.plugins.init` registers for `stylized`, gives the integrator
a `render` of its own (`ResolvingRender`) that pins the style's scene-relative `auto` values
(`scene.defaults.resolve_defaults`) once per scene and hands the call to the resolved integrator,
which has no such `render`. The pipeline never renders with this object (`pipeline.resolve`).
Design: docs/design/standalone_render.md.
"""
from __future__ import annotations

import weakref

from styletrace.gate import mi
from styletrace.kernel.integrator import StylizedIntegrator
from styletrace.scene.defaults import resolve_defaults


def scene_key(scene: mi.Scene) -> tuple:
    """What identifies the scene a resolution belongs to, keeping no reference to it (see
    `StylizedIntegrator.sample`).

    Args:
        scene: the mi.Scene.

    Returns:
        (id(scene), its film's crop size, its crop offset; both () without a sensor): a crop
        changes the pilot.
    """
    film = scene.sensors()[0].film() if scene.sensors() else None
    size = tuple(int(v) for v in film.crop_size()) if film is not None else ()
    offset = tuple(int(v) for v in film.crop_offset()) if film is not None else ()
    return id(scene), size, offset


class ResolvingRender:
    """The `render` a Mitsuba-built integrator gets (module doc). It holds its integrator weakly,
    and the resolved integrator it caches holds no scene object: no reference cycle
    (docs/design/standalone_render.md).

    Args:
        integrator: the StylizedIntegrator whose `render` this is.
    """

    def __init__(self, integrator: StylizedIntegrator):
        self.owner = weakref.ref(integrator)
        self.resolved_for: tuple | None = None

    def __call__(self, scene, sensor=0, seed=0, spp=0, develop=True, evaluate=True):
        """`mi.render`'s call: render with the owner's values, `auto` values pinned on `scene`
        (cached per `scene_key`)."""
        key = scene_key(scene)
        if self.resolved_for is None or self.resolved_for[0] != key:
            fresh = StylizedIntegrator.from_values(self.owner().values)
            self.resolved_for = (key, resolve_defaults(scene, fresh)[0])
        return self.resolved_for[1].render(scene, sensor, seed, spp, develop, evaluate)


def from_properties(props: mi.Properties) -> StylizedIntegrator:
    """The factory of `stylized`: an integrator whose `mi.render` resolves `auto` values.

    Args:
        props: the integrator's mi.Properties (from a scene file or dict).

    Returns:
        The StylizedIntegrator, its `render` a `ResolvingRender`.

    Raises:
        SettingsError, StyleError: properties the integrator refuses.
    """
    integrator = StylizedIntegrator(props)
    integrator.render = ResolvingRender(integrator)
    return integrator


__all__ = ["from_properties", "ResolvingRender", "scene_key"]
