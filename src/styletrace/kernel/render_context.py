"""The per-render state of a `stylized` integrator, bound to one scene for one render and
always released.

    # in `sample`, `reuse.render_reuse`, and a recording through them
    with RenderContext(integrator, scene):
        # integrator.targets, .emitters, .lines, .view, ... are set
        ... trace ...

While a kernel is traced the integrator's methods read what the scene decides: the style targets
(which BSDFs are styled, `targets_for`), whether the scene has media or null surfaces, the emitter
sampler, the feature-line detector (West 2021's cone, or LLaT's lifted line types) and the line
state per stylized level, LLaT's image-coordinate tracer and its state per level (only where a style
reads the coordinate: anchors.py), the camera's forward vector, the expansion pass's lane moments
and the adaptive statistics, and the configuration every walk of the render shares
(path.WalkConfig). This is the one place that sets them and the one place that clears them: Dr.Jit
traces calls on every live instance of a class, and a BSDF or emitter of a scene the garbage
collector is tearing down, still held by an integrator after its render, crashed a later trace
(measured: a segfault in pdf_emitter_direction). No reference to the scene's objects outlives the
context.
"""
from __future__ import annotations

from styletrace.errors import SceneError
from styletrace.gate import mi
from styletrace.kernel.anchors import Tone
from styletrace.kernel.emitter_sampler import EmitterSampler
from styletrace.kernel.lifted_lines import Lifted
from styletrace.kernel.lines import Lines
from styletrace.kernel.path import WalkConfig
from styletrace.kernel.scene_graph import SceneGraph
from styletrace.styles.base import camera_forward


class RenderContext:
    """Binds `scene` to one render of `integrator` (see the module doc); re-entering it is
    an error."""

    def __init__(self, integrator, scene: mi.Scene):
        self.integrator, self.scene = integrator, scene

    def __enter__(self) -> "RenderContext":
        integ, scene = self.integrator, self.scene
        if integ.targets:
            raise RuntimeError(
                "a stylized integrator renders one scene at a time: its render context is taken"
            )
        try:
            graph = SceneGraph(scene)
            # plain flags only: a kept reference to a scene's objects breaks later traces
            # (module doc)
            integ.nulls, integ.media, integ.see_through = (
                graph.has_null,
                graph.has_media,
                graph.has_see_through,
            )
            integ.targets = integ.targets_for(scene, graph)
            problem = integ.scene_problem()
            if problem is not None:
                raise SceneError(problem)
            settings = integ.settings
            lifted = settings.lines is not None and settings.lines.mode == "lifted"
            integ.lines = (
                None
                if settings.lines is None or lifted
                else Lines(settings.lines, scene, see_through=integ.see_through)
            )
            # LLaT's conditional lifting tests its line types per camera sample before L
            # (lifted_lines.py)
            integ.lifted = (
                Lifted(
                    scene,
                    settings.lines.types,
                    depth=settings.lines.depth,
                    through_diffuse=settings.lines.diffuse,
                    objects=settings.lines.objects,
                )
                if lifted and scene.sensors()
                else None
            )
            wants = any(getattr(t.slot.style, "wants_coordinate", False) for t in integ.targets)
            integ.tone = Tone(scene) if wants and scene.sensors() else None
            integ.tone_states = {}
            # emitter selection in an order of the scene's own (its emitter list changes order
            # between runs)
            integ.emitters = EmitterSampler(scene, settings.emitter_sampling)
            integ.walk_config = WalkConfig(scene, integ.emitters, settings.max_depth,
                                           settings.rr_depth, nulls=integ.nulls, media=integ.media)
            integ.view = camera_forward(scene)
            integ.line_states = {}
            integ._lane_moments = None
            integ._stats = []
        except BaseException:
            self.release()
            raise
        return self

    def release(self) -> None:
        integ = self.integrator
        integ.targets = []
        integ.emitters = None
        integ.walk_config = None
        integ.lines, integ.line_states = None, {}
        integ.lifted = None
        integ.tone, integ.tone_states = None, {}
        integ._lane_moments = None
        integ._stats = []

    def __exit__(self, *exc) -> bool:
        self.release()
        return False


__all__ = ["RenderContext"]
