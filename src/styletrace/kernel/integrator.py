"""`stylized`: Mitsuba integrator for the stylized rendering equation (depth-first tree sampling).

    L(x, wo) = g_theta( L_e(x, wo) + \\int f(x, wi, wo) L_i(x, wi) cos dwi )

At a stylized vertex n children of g's argument are drawn in a nested loop in the same SIMD lane
and handed to the style's estimator. `stylize` chooses the vertices: first_hit, first_n_hits (the
first `stylize_depth` vertices of every path, recursively) or first_object_hit (the first vertex
on a styled object, at any depth). Properties (XML, dict, the CLI's --set) are parsed by
`config.settings`. With first_hit a camera ray's first real collision in a medium is stylized
too (volume.Collision). Escaped rays see the environment unstylized; with `hide_emitters` camera
rays pass through area lights. Media: volume.py; lines: line_hooks.py; expansion pass:
expansion.py; light groups (each group's light its own expectation, styled by its own style):
light_groups.py, `stylized_groups`.
Design: docs/design/stylized_integrator.md.
"""
from __future__ import annotations

from dataclasses import replace

from styletrace.config import settings as S
from styletrace.config.estimator_registry import firefly_cap, make_estimator
from styletrace.gate import dr, mi
from styletrace.kernel.bounce import bounce
from styletrace.kernel.error_aovs import AOV_NAMES, error_aovs
from styletrace.kernel.expansion import Expansion
from styletrace.kernel.expansion import moments as pass_moments
from styletrace.kernel.lane_sampler import LaneSampler
from styletrace.kernel.light_groups import run_groups
from styletrace.kernel.line_hooks import CameraSample, camera_edge, line_problem, walk_lines
from styletrace.kernel.line_hooks import lifted as lifted_lines
from styletrace.kernel.owen_sobol_sampler import OwenSobolSampler
from styletrace.kernel.path import (
    NO_HOOKS,
    Hooks,
    Start,
    first_scattering,
    past_area_emitters,
    walk,
)
from styletrace.kernel.render_context import RenderContext
from styletrace.kernel.scene_graph import SceneGraph
from styletrace.kernel.scene_graph import any_ptr as _any_ptr
from styletrace.kernel.vertex import Site, emission, environment
from styletrace.kernel.volume import collision_site, volume_walk
from styletrace.styles.base import Vertex

#: Dr.Jit's JitFlag.OptimizeLoops while styletrace traces its kernels (True only to measure what it
#: costs: benchmarks/recursion_depth.py, tests/kernel/test_recursion_depth.py)
OPTIMIZE_LOOPS = False


def tracing():
    """The Dr.Jit flags under which styletrace traces its kernels, scoped (a user's own Dr.Jit code
    keeps its settings): OptimizeLoops as OPTIMIZE_LOOPS, off (with it the trace time doubled per
    stylized level; the images are bit-identical either way).
    Design: docs/design/stylized_integrator.md.

    Returns:
        A context manager.
    """
    return dr.scoped_set_flag(dr.JitFlag.OptimizeLoops, OPTIMIZE_LOOPS)


class Target:
    """Where one style slot applies: everywhere else (`bsdfs` empty) or on objects with
    these BSDFs.

    Args:
        slot: the style slot (style, inner count, estimator).
        bsdfs: the styled BSDF first, then the wrappers an intersection reports for it; empty:
            every object no other target claims.
        emitters: the emitters of its shapes, which first_object_hit's walks leave to g.
    """

    def __init__(self, slot: S.StyleSlot, bsdfs=(), emitters=()):
        self.slot, self.bsdfs, self.emitters = slot, list(bsdfs), list(emitters)


class StylizedIntegrator(mi.SamplingIntegrator):
    """The `stylized` integrator (module docstring).

    Args:
        props: Mitsuba properties (XML, dicts), parsed by `settings.parse` unless `settings` is
            given.
        settings: settings already parsed from `values` (the Python API and the CLI parse once).
        values: the property values as given (default: those of `props`), kept so front ends can
            refine the integrator (`settings.refine`).

    Raises:
        SettingsError: a property is unknown or has a bad value.
    """
    # per-render state, set and cleared by `render_context.RenderContext` only (its module doc
    # says why)
    targets = ()         # the style targets of the scene being traced
    emitters = None      # its emitter sampler
    # path.WalkConfig: what every walk of the render shares (scene, emitters, depths)
    walk_config = None
    view = None          # its camera's forward vector
    # null-scattering surfaces / participating media / pure null BSDFs
    nulls = media = see_through = False
    lines = None         # feature lines bound to the scene being traced (lines.py), else None
    # line_mode lifted: LLaT's line types bound to the scene (lifted_lines.py), else None
    lifted = None
    # lines.LineState at the vertex of each stylized level (-1: the camera), while tracing
    line_states = {}
    tone = None          # anchors.Tone where a style reads image coordinates (Vertex.s), else None
    # anchors.ToneState at the vertex of each stylized level (-1: the camera), while tracing
    tone_states = {}
    # light_groups.GroupTable of the scene being traced where light groups are declared, else None
    light_table = None
    # each group's value at the first stylized vertex of the camera sample being traced
    group_values = None
    #: lanes where a line fired on the camera ray trace nothing more (False only to measure the
    #: saving: benchmarks/lines_cost.py)
    line_short_circuit = True

    def __init__(
        self, props: mi.Properties, settings: S.Settings | None = None, values: dict | None = None
    ):
        super().__init__(props)
        # the values as given, so front ends can refine this integrator (`settings.refine`)
        self.values = S.properties_of(props) if values is None else dict(values)
        self.settings: S.Settings = settings if settings is not None else S.parse(self.values)
        if self.settings.reuse != "off":  # Mitsuba's own render loop otherwise, untouched
            self.render = self._render_reuse
        self.expansion = Expansion()  # the expansion pass's per-pixel moments (expansion_pass > 0)
        self._lane_moments = None

    @classmethod
    def from_values(cls, values: dict) -> "StylizedIntegrator":
        """A `stylized` integrator from property values (style, style parameters,
        inner_samples, ...).

        Args:
            values: property values by name; a "type" entry is ignored.

        Returns:
            StylizedIntegrator.

        Raises:
            SettingsError: a value is unknown or bad.
        """
        values = {k: v for k, v in values.items() if k != "type"}
        return cls(mi.Properties(), S.parse(values), values)

    def prepare_expansion(self, scene: mi.Scene, seed: int):
        """Run the expansion pass for the scene's current film crop (once per crop and seed; a no-op
        with expansion_pass 0).

        Args:
            scene: the scene about to be rendered, its film cropped to the tile.
            seed: the expansion pass's seed (`pipeline.passes.expansion_seed`).

        Returns:
            Its `expansion.Moments`, or None with expansion_pass 0.
        """
        m = self.settings.expansion_pass
        return self.expansion.prepare(self, scene, m, int(seed)) if m else None

    # ---- which styles apply where --------------------------------------------------------------
    def targets_for(self, scene: mi.Scene, graph: SceneGraph | None = None) -> list[Target]:
        """Which style applies where in `scene`: its styled BSDFs wherever they sit (in wrappers,
        in shapegroups: scene_graph.py; `bsdfs[0]` is the styled BSDF itself), then the
        integrator's own style for all other objects (not with first_object_hit).

        Args:
            scene: the scene. graph: its SceneGraph, if built already.

        Returns:
            list[Target].

        Raises:
            SceneError: the scene graph refuses the scene's styling (SceneGraph).
        """
        graph = SceneGraph(scene) if graph is None else graph
        targets = [
            Target(styled.slot, pointers, emitters) for styled, pointers, emitters in graph.styled
        ]
        if self.settings.stylize != "first_object_hit":
            targets.append(Target(self.settings.slot))  # the integrator's style: all other objects
        return targets

    def styled_mask(self, si) -> mi.Bool:
        """Lanes whose surface has a styled BSDF (any target's).

        Args:
            si: the lanes' surface interactions.

        Returns:
            mi.Bool.
        """
        return _any_ptr(si.bsdf(), [b for t in self.targets for b in t.bsdfs], mi.BSDFPtr)

    def _skip_emitter(self, ds) -> mi.Bool:
        return _any_ptr(ds.emitter, [e for t in self.targets for e in t.emitters], mi.EmitterPtr)

    # ---- the tree ------------------------------------------------------------------------------
    def _walk(self, sampler, start: Start, active, hooks: Hooks = NO_HOOKS):
        """path.walk, or volume.py's walk where the scene has media (a trace-time switch: scenes
        without media trace exactly the plain kernel); both take the render's `walk_config`."""
        cfg = self.walk_config
        return (volume_walk if cfg.media else walk)(cfg, sampler, start, active, hooks)

    def child(self, level: int, sampler, site: Site, active) -> mi.Spectrum:
        """One sample of L_e(x) + \\int f L_i at the level-`level` vertex x = `site`: an ordinary
        walk below the last level, else a step to the next level's vertex, stylized in turn.

        Args:
            level: the stylized level of x (0: the first).
            sampler: the lane's random stream (the child draws from its `split()`). site: the
                vertex x.
            active: the lanes that draw (mi.Bool).

        Returns:
            mi.Spectrum.
        """
        s = self.settings
        # a stream of its own where the sampler has streams (SequenceSampler.split)
        sampler = sampler.split()
        if level + 1 >= s.stylize_depth:
            start = Start(site.pi, site.ray, site.depth, opaque=True, medium=site.medium,
                          collision=site.collision)
            return self._walk(sampler, start, active, Hooks(lines=walk_lines(self, level))).L
        if s.stylize == "first_object_hit":
            start = Start(site.pi, site.ray, site.depth, medium=site.medium)
            return self.walk(level + 1, sampler, start, active, halt_at_start=False)
        if self.media:
            # first_n_hits through media: x samples delta lights only, its BSDF sample flies through
            # the media to the next surface vertex, stylized at the next level; a lane that scatters
            # in a medium on the way goes on as an ordinary volumetric path (volume.py)
            first = mi.UInt32(site.depth)
            start = Start(
                site.pi, site.ray, site.depth, opaque=True, medium=site.medium, delta=True
            )
            w = self._walk(sampler, start, active, Hooks(stop=lambda si2, d: d == first + 1,
                                                         lines=walk_lines(self, level),
                                                         tone=self.tone_states.get(level)))
            if self.lines is not None:
                self.line_states[level + 1] = w.lines
            self.tone_states[level + 1] = w.tone
            si2 = w.pi.compute_surface_interaction(
                w.ray, ray_flags=mi.RayFlags.All, active=w.halted
            )
            deeper = self.stylized(
                level + 1, sampler, Site(w.pi, si2, w.ray, w.depth, w.medium), w.halted
            )
            return w.L + dr.select(w.halted, w.beta * deeper, 0.0)
        # first_n_hits: one bounce to the next vertex, which is stylized as well
        b = bounce(self.walk_config, sampler, site, active,
                   Hooks(lines=walk_lines(self, level), tone=self.tone_states.get(level)))
        if self.lines is not None:
            self.line_states[level + 1] = b.lines
        self.tone_states[level + 1] = b.tone
        deeper = self.stylized(level + 1, sampler, Site(b.pi, b.si, b.ray, site.depth + 1), b.hit)
        scene = self.walk_config.scene
        return b.L + dr.select(
            b.go, b.weight * dr.select(b.hit, deeper, environment(scene, b.si, b.go)), 0.0
        )

    def walk(self, level: int, sampler, start: Start, active, halt_at_start: bool) -> mi.Spectrum:
        """A path-traced walk from `start` that halts on styled objects, stylized at `level`.

        Args:
            level: the stylized level of the vertices it halts at.
            sampler: the lane's random stream. start: where the walk starts.
            active: the lanes that walk (mi.Bool).
            halt_at_start: halt at the start vertex too; else it scatters by its opaque part.

        Returns:
            The walk's radiance (mi.Spectrum), the stylized values included.
        """
        first = mi.UInt32(start.depth)

        def stop(si, d):
            styled = self.styled_mask(si)
            return styled if halt_at_start else styled & (d > first)

        hooks = Hooks(stop=stop, skip_emitter=self._skip_emitter, lines=walk_lines(self, level - 1),
                      tone=self.tone_states.get(level - 1))
        w = self._walk(sampler, replace(start, opaque=not halt_at_start), active, hooks)
        if self.lines is not None:
            self.line_states[level] = w.lines
        self.tone_states[level] = w.tone
        si = w.pi.compute_surface_interaction(w.ray, ray_flags=mi.RayFlags.All, active=w.halted)
        value = self.stylized(level, sampler, Site(w.pi, si, w.ray, w.depth, w.medium), w.halted)
        return self.through(w, value)

    def through(self, w, value) -> mi.Spectrum:
        """The walk's radiance: what it gathered before halting plus its throughput times the
        stylized value where it halted (a seam for `lookdev.record`, which keeps both per
        camera sample).

        Args:
            w: a finished path.Walk. value: the stylized value where it halted (mi.Spectrum).

        Returns:
            mi.Spectrum.
        """
        return w.L + dr.select(w.halted, w.beta * value, 0.0)

    def stylized(self, level: int, sampler, site: Site, active) -> mi.Spectrum:
        """g(E[L_o]) at the level-`level` vertex `site`, each object with its own style.

        Args:
            level: the stylized level (0: the first).
            sampler: the lane's random stream. site: the vertex.
            active: the lanes at a vertex to stylize (mi.Bool).

        Returns:
            mi.Spectrum, 0 where not active or where no target applies.
        """
        if self.light_table is not None:
            return self.stylized_groups(level, sampler, site, active)
        si, ray, depth = site.si, site.ray, site.depth
        v = Vertex(p=si.p, n=mi.Vector3f(si.sh_frame.n), wo=-ray.d, view=mi.Vector3f(self.view),
                   depth=mi.UInt32(depth))
        # LLaT's image coordinate (anchors.py), traced only where a style reads it
        if self.tone is not None:
            v.s, v.method = self.tone.coordinate(self.walk_config.scene, si, ray, depth,
                                                 self.tone_states.get(level), active)
        styled = self.styled_mask(si) if len(self.targets) > 1 else mi.Bool(False)
        total = mi.Spectrum(0.0)
        for target in self.targets:
            here = active & (
                _any_ptr(si.bsdf(), target.bsdfs, mi.BSDFPtr) if target.bsdfs else ~styled
            )
            total = dr.select(
                here, self.estimate(target.slot, level, sampler, site, here, v), total
            )
        return total

    def stylized_groups(self, level: int, sampler, site: Site, active) -> mi.Spectrum:
        """The sum over light groups of g_k(E[L_k]) at `site` (first_hit, one target: the
        settings and render_context refuse the rest): one child walk per draw, its radiance split
        by group, each group's estimator fed its own part (light_groups.run_groups). Keeps each
        group's value in `group_values` for the AOVs.

        Args:
            level: the stylized level (0). sampler: the lane's random stream. site: the vertex.
            active: the lanes at a vertex to stylize (mi.Bool).

        Returns:
            mi.Spectrum, 0 where not active.
        """
        si, ray = site.si, site.ray
        v = Vertex(p=si.p, n=mi.Vector3f(si.sh_frame.n), wo=-ray.d, view=mi.Vector3f(self.view),
                   depth=mi.UInt32(site.depth))
        if self.tone is not None:  # as in `stylized`
            v.s, v.method = self.tone.coordinate(self.walk_config.scene, si, ray, site.depth,
                                                 self.tone_states.get(level), active)
        # the integrator's slot as pinned (scene.defaults replaces it), then the groups' own
        slots = [self.settings.slot] + [g.slot for g in self.settings.light_groups[1:]]
        start = Start(site.pi, site.ray, site.depth, opaque=True)
        hooks = Hooks(groups=self.light_table)

        def draw(carry):
            (smp,) = carry
            xs = self._walk(smp.split(), start, active, hooks).Lg
            xs = [slot.style.apply(x, v) if slot.style.per_sample else x
                  for slot, x in zip(slots, xs)]
            return xs, (smp,)

        def uniform(carry):
            (smp,) = carry
            return smp.next_1d(), (smp,)

        estimators = [make_estimator(slot, level, v, self.settings) for slot in slots]
        values, _ = run_groups(estimators, draw, (sampler,), uniform, active, like=mi.Color3f)
        values = [dr.select(active, x, 0.0) for x in values]
        self.group_values = values
        total = values[0]
        for x in values[1:]:
            total = total + x
        return total

    def estimate(self, slot: S.StyleSlot, level, sampler, site: Site, active, v) -> mi.Spectrum:
        """The slot's estimate of g(E[L_o]) at `site` on the `active` lanes. In the expansion pass
        series slots at level 0 only collect their children's moments, and every slot gives 0 there.

        Args:
            slot: the style slot. level: the stylized level.
            sampler: the lane's random stream. site: the vertex.
            active: the lanes where the slot applies (mi.Bool). v: the style's Vertex.

        Returns:
            mi.Spectrum.
        """
        scene, si = self.walk_config.scene, site.si
        style = slot.style
        if style.closed_form:  # no children: the AOVs keep 0 here
            return style.apply(mi.Color3f(0.0), v)

        def draw(carry):
            (smp,) = carry
            x = self.child(level, smp, site, active)
            if style.per_sample:
                x = style.apply(x, v)
            return x, (smp,)

        def uniform(carry):
            (smp,) = carry
            return smp.next_1d(), (smp,)

        collector = self.expansion.collector
        # the expansion pass: the first vertex's moments only
        if collector is not None and level == 0:
            if slot.estimator == "series":
                s1, s2 = pass_moments(
                    lambda smp: draw((smp,))[0],
                    sampler,
                    active,
                    collector.children,
                    emission(scene, si, active),
                )
                collector.add(dr.width(site.ray.d), active, s1, s2)
            return mi.Color3f(0.0)
        moments = None
        # the pass's moments of x - e, and this vertex's e
        if level == 0 and self._lane_moments is not None:
            moments = (self._lane_moments, emission(scene, si, active))
        emitted = emission(scene, si, active) if firefly_cap(self.settings) else None
        est = make_estimator(slot, level, v, self.settings, moments, emitted)
        value, _ = est.run(draw, (sampler,), uniform, active, like=mi.Color3f)
        # AdaptiveDirect's; none for a styled object's other estimator
        stats = getattr(est.inner, "stats", None)
        if level == 0 and self.settings.aovs and stats is not None:
            self._stats.append((active, stats))
        return value

    def _render_reuse(self, scene, sensor=0, seed=0, spp=0, develop=True, evaluate=True):
        """`render` with reuse=pixels: a pass is rendered by `reuse.render_reuse`, which needs every
        camera sample's neighbours at once (Mitsuba's loop calls `sample`, whose lanes cannot see
        each other). Set on the instance only then (docs/design/stylized_integrator.md)."""
        from styletrace.kernel import reuse
        sensor = scene.sensors()[sensor] if isinstance(sensor, int) else sensor
        with tracing():
            image = reuse.render_reuse(
                self, scene, sensor, int(seed), int(spp) or int(sensor.sampler().sample_count())
            )
        return image if develop else mi.TensorXf()

    def sample(self, scene, sampler, ray, medium=None, active=True):
        # binds the scene's targets, emitters, lines, view; always releases them
        with RenderContext(self, scene):
            if medium is None and scene.sensors():
                medium = scene.sensors()[0].get_medium()
            with tracing():
                return self._sample(scene, sampler, ray, active, medium)

    def scene_problem(self) -> str | None:
        """Why this integrator cannot render the scene bound to it (its lines with media),
        or None."""
        return line_problem(self.settings, self.media)

    def _sample(self, scene, sampler, ray, active, medium=None):
        # (lanes, AdaptiveDirect.stats) of each style slot at the first stylized vertex
        self._stats = []
        value, valid, _ = self._radiance(scene, sampler, ray, active, medium)
        aovs = error_aovs(value, self._stats) if self.settings.aovs else []
        self._stats = []
        if self.light_table is not None:  # each group's Combined (its channels: `aov_names`)
            aovs = [c for x in self.group_values for c in (x.x, x.y, x.z)]
            self.group_values = None
        return value, valid, aovs

    def _radiance(self, scene, sampler, ray, active, medium=None):
        for t in self.targets:
            t.slot.style.prepare(scene)
        for g in self.settings.light_groups[1:]:
            g.slot.style.prepare(scene)
        camera_ray, spp = ray, sampler.sample_count()
        ray = mi.Ray3f(ray)
        active = mi.Bool(active)
        # every random decision below the camera ray: the sequence the camera sample came from
        # (`owen_sobol`), else an independent stream per lane
        sampler = (sampler.lanes() if isinstance(sampler, OwenSobolSampler)
                   else LaneSampler.seeded_from(sampler, dr.width(ray.d)))
        m = self.settings.expansion_pass
        # the lane's pixel's moments from the expansion pass (none while that pass itself
        # is rendered)
        self._lane_moments = (self.expansion.lookup(scene, dr.width(ray.d), m)
                              if m and self.expansion.collector is None else None)
        if self.lines is None and self.lifted is None:
            return self._stylize(scene, sampler, ray, active, medium)
        camera = CameraSample(camera_ray, spp, medium)
        hook = lifted_lines if self.lifted is not None else camera_edge
        return hook(self, self._stylize, scene, sampler, camera, ray, active)

    def _stylize(self, scene, sampler, ray, active, medium=None):
        pi = scene.ray_intersect_preliminary(ray, coherent=True, active=active)
        hide = self.settings.hide_emitters
        if hide:
            ray, pi = past_area_emitters(scene, ray, pi, active)
        if self.tone is not None:
            start = self.tone.start(ray, pi, active)
            self.tone_states = {-1: start, 0: start}
        # alpha, as Mitsuba's `path`: the camera ray found a surface, or a visible environment
        valid = active & (pi.is_valid() | (scene.environment() is not None and not hide))
        if self.settings.stylize == "first_object_hit":
            # the walk hides what it meets before its first scattering (a medium scatters too)
            if self.media:
                start = Start(pi, ray, mi.UInt32(0), medium=medium, flight=True, hide=hide)
                return self.walk(0, sampler, start, active, halt_at_start=True), valid, []
            start = active & pi.is_valid() if hide else active  # a hidden environment is black
            return (
                self.walk(0, sampler, Start(pi, ray, mi.UInt32(0)), start, halt_at_start=True),
                valid,
                [],
            )
        if self.media:
            # first_hit: the stylized vertex is the first scattering, on a surface or at a real
            # collision in a medium (volume.Collision: the integrator's style, of albedo x the
            # in-scattered light), so what is seen in a medium follows g as surfaces do. A
            # closed-form style reads only the vertex, of which a collision has no normal or
            # object, and first_n_hits the next surface: there, as before, lanes that scatter in a
            # medium first go on as ordinary volumetric paths (volume.py). The others carry the
            # transmittance. Design: docs/design/participating_media.md.
            s = self.settings
            in_medium = ((lambda d: d == 0)
                         if s.stylize == "first_hit" and not s.style.closed_form else None)
            w = self._walk(
                sampler,
                Start(pi, ray, 0, medium=medium, flight=True, hide=hide),
                active,
                Hooks(stop=lambda si, d: d == 0, halt_in_medium=in_medium),
            )
            si = w.pi.compute_surface_interaction(w.ray, ray_flags=mi.RayFlags.All, active=w.halted)
            if w.collision is not None:
                si = collision_site(si, w.collision, w.ray)
            site = Site(w.pi, si, w.ray, mi.UInt32(0), w.medium, w.collision)
            value = self.stylized(0, sampler, site, w.halted)
            return self.through(w, value), valid | w.halted | (active & (w.depth > 0)), []
        if self.nulls:  # the stylized vertex is the first that scatters (path.first_scattering)
            front = first_scattering(scene, sampler, pi, ray, active)
            pi, ray = front.pi, front.ray
        si = pi.compute_surface_interaction(ray, ray_flags=mi.RayFlags.All, active=active)
        hit = active & si.is_valid()
        value = self.stylized(0, sampler, Site(pi, si, ray, mi.UInt32(0)), hit)
        sky = 0.0 if hide else environment(scene, si, active)
        value = dr.select(hit, value, sky)
        if self.nulls:
            value = front.beta * value
        if self.light_table is not None:  # the environment seen directly: its group's
            env = self.light_table.environment
            self.group_values = [
                (front.beta if self.nulls else 1.0) * dr.select(hit, x, sky if k == env else 0.0)
                for k, x in enumerate(self.group_values)
            ]
        return value, valid, []

    def aov_names(self):
        if self.settings.light_groups:  # each group's Combined, R G B (`group_names` order)
            return [f"{g}.{c}" for g in self.group_names() for c in "RGB"]
        return list(AOV_NAMES) if self.settings.aovs else []

    def group_names(self) -> list[str]:
        """The light groups' names, `default` first (their AOVs' order); [] without groups."""
        return [g.name for g in self.settings.light_groups]

    def to_string(self):
        return f"StylizedIntegrator[{self.settings.describe()}]"
