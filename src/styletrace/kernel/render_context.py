"""The per-render state of a `stylized` integrator, bound to one scene for one render and
always released.

    # in `sample`, `reuse.render_reuse`, and a recording through them
    with RenderContext(integrator, scene):
        # integrator.targets, .emitters, .lines, .view, ... are set
        ... trace ...

It sets what the integrator's methods read while a kernel is traced (style targets, media and null
flags, emitter sampler, line and tone tracers and their states, walk configuration, camera vector,
expansion moments, adaptive statistics), and it alone clears them: no reference to the scene's
objects outlives it. Design: docs/design/render_state.md.
"""
from __future__ import annotations

from styletrace.errors import SceneError
from styletrace.gate import mi
from styletrace.kernel.anchors import Tone
from styletrace.kernel.emitter_sampler import EmitterSampler
from styletrace.kernel.lifted_lines import Lifted
from styletrace.kernel.light_groups import check_scene as check_groups
from styletrace.kernel.lines import Lines
from styletrace.kernel.path import WalkConfig
from styletrace.kernel.scene_graph import SceneGraph
from styletrace.styles.base import camera_forward


class RenderContext:
    """Binds `scene` to one render of `integrator` (see the module doc).

    Args:
        integrator: the `stylized` integrator. scene: the scene it renders.

    Raises:
        RuntimeError: on entering, where the integrator's render context is taken already.
        SceneError: on entering, where the scene cannot be rendered (its styling, lines, media).
    """

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
            groups = settings.light_groups
            # each emitter's light group (None: no group declared, nothing of them is traced)
            integ.light_table = check_groups(scene, groups, graph)
            styles = [t.slot.style for t in integ.targets] + [g.slot.style for g in groups[1:]]
            wants = any(getattr(style, "wants_coordinate", False) for style in styles)
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
        integ.light_table, integ.group_values = None, None

    def __exit__(self, *exc) -> bool:
        self.release()
        return False


__all__ = ["RenderContext"]
