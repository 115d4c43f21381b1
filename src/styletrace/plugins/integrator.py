"""`stylized`: Mitsuba integrator for the stylized rendering equation (depth-first tree sampling).

Properties (XML, Python dict, or the CLI's --set): `style`, the style's own parameters under their
registry names, `inner_samples`, `estimator`, `stylize`, `stylize_depth`, `max_depth`, `rr_depth`,
`hide_emitters`.
Their defaults, parsing and docs live in `settings` (the table in the README is generated from it).

The radiance leaving a stylized vertex x towards the viewer is
    L(x, wo) = g_theta( L_e(x, wo) + \\int f(x, wi, wo) L_i(x, wi) cos dwi )
(the stylized rendering equation, emission inside g). At a stylized vertex the integrator draws n
child estimates of the argument of g in a nested symbolic loop in the same SIMD lane (no lane
replication, so memory does not grow with n) and hands them to the estimator.

Where styles apply (`stylize`):
- first_hit: the camera ray's first hit. Objects whose BSDF is a `styled` wrapper use their own style
  there; all other objects use the integrator's style.
- first_n_hits: the first N = stylize_depth vertices of every path, recursively (a child of a level-l
  vertex takes one BSDF-sampled bounce to the level-(l+1) vertex; children of the last level are
  ordinary path-traced samples). Cost per camera sample is the product of the per-level counts.
- first_object_hit: the first vertex *on a styled object* along each path, at any depth: a stylized
  object seen through a mirror or a glass is still stylized. Paths are ordinary path-traced walks that
  halt on styled objects; with N > 1 the children halt again on the next styled object, N levels deep.
  The integrator's own style must be identity here.

Rays that escape see the environment unstylized. With `hide_emitters` camera rays (only they) pass
through area lights and see black where they escape, as in Mitsuba's `path`.
"""
from __future__ import annotations

import drjit as dr
import mitsuba as mi

from ..styles.base import Vertex, camera_forward
from . import settings as S
from .emitter_sampler import EmitterSampler
from .estimation import make_estimator
from .lane_sampler import LaneSampler
from .path import bounce, environment, first_scattering, past_area_emitters, walk
from ..errors import SceneError
from .scene_graph import SceneGraph, any_ptr as _any_ptr


class Target:
    """Where one style slot applies: everywhere else (`bsdfs` empty) or on objects with these BSDFs."""

    def __init__(self, slot: S.StyleSlot, bsdfs=(), emitters=()):
        self.slot, self.bsdfs, self.emitters = slot, list(bsdfs), list(emitters)


class StylizedIntegrator(mi.SamplingIntegrator):
    def __init__(self, props: mi.Properties, settings: S.Settings | None = None, values: dict | None = None):
        """From Mitsuba properties (XML, dicts), or from `settings` already parsed from `values`
        (`S.parse(values)`; the Python API and the CLI build it this way, parsing once)."""
        super().__init__(props)
        # the values as given, so front ends can refine this integrator (`settings.refine`)
        self.values = S.properties_of(props) if values is None else dict(values)
        self.settings: S.Settings = settings if settings is not None else S.parse(self.values)
        if self.settings.reuse != "off":  # Mitsuba's own render loop otherwise, untouched
            self.render = self._render_reuse

    @classmethod
    def from_values(cls, values: dict) -> "StylizedIntegrator":
        """A `stylized` integrator from property values (style, style parameters, inner_samples, ...)."""
        values = {k: v for k, v in values.items() if k != "type"}
        return cls(mi.Properties(), S.parse(values), values)

    # ---- which styles apply where --------------------------------------------------------------
    def _targets(self, scene: mi.Scene) -> list[Target]:
        # styled BSDFs wherever they sit: on shapes, inside wrappers (twosided, mask, blendbsdf) and in
        # shapegroups seen through instances (scene_graph.py); `bsdfs[0]` is the styled BSDF itself
        graph = SceneGraph(scene)
        if graph.has_media:  # refused, not ignored (also checked before rendering: arguments.check_passes_args)
            raise SceneError(MEDIA_REFUSED)
        # plain flags only: a kept reference to a scene's objects breaks later traces (see `sample`)
        self.nulls, self.media = graph.has_null, graph.has_media
        targets = [Target(styled.slot, pointers, emitters) for styled, pointers, emitters in graph.styled]
        if self.settings.stylize != "first_object_hit":
            targets.append(Target(self.settings.slot))  # the integrator's style: all other objects
        return targets

    def _styled(self, si) -> mi.Bool:
        return _any_ptr(si.bsdf(), [b for t in self.targets for b in t.bsdfs], mi.BSDFPtr)

    def _skip_emitter(self, ds) -> mi.Bool:
        return _any_ptr(ds.emitter, [e for t in self.targets for e in t.emitters], mi.EmitterPtr)

    # ---- the tree ------------------------------------------------------------------------------
    def child(self, level: int, scene, sampler, pi, si, ray, active, depth) -> mi.Spectrum:
        """One sample of L_e(x) + \\int f L_i at the level-`level` vertex x (`pi`/`si` along `ray`)."""
        s = self.settings
        if level + 1 >= s.stylize_depth:
            return walk(scene, sampler, pi, ray, active, s.max_depth, s.rr_depth, depth, emitters=self.emitters,
                        nulls=self.nulls, opaque_start=True).L
        if s.stylize == "first_object_hit":
            return self.walk(level + 1, scene, sampler, pi, ray, active, depth, halt_at_start=False)
        # first_n_hits: one bounce to the next vertex, which is stylized as well
        b = bounce(scene, sampler, si, ray, active, depth, s.max_depth, self.emitters, self.nulls)
        deeper = self.stylized(level + 1, scene, sampler, b.pi, b.si, b.ray, b.hit, depth + 1)
        return b.L + dr.select(b.go, b.weight * dr.select(b.hit, deeper, environment(scene, b.si, b.go)), 0.0)

    def walk(self, level: int, scene, sampler, pi, ray, active, depth, halt_at_start: bool) -> mi.Spectrum:
        """A path-traced walk that halts on styled objects and stylizes them at `level`."""
        s = self.settings
        start = mi.UInt32(depth)

        def stop(si, d):
            styled = self._styled(si)
            return styled if halt_at_start else styled & (d > start)

        w = walk(scene, sampler, pi, ray, active, s.max_depth, s.rr_depth, depth, stop=stop,
                 skip_emitter=self._skip_emitter, emitters=self.emitters, nulls=self.nulls,
                 opaque_start=not halt_at_start)
        si = w.pi.compute_surface_interaction(w.ray, ray_flags=mi.RayFlags.All, active=w.halted)
        value = self.stylized(level, scene, sampler, w.pi, si, w.ray, w.halted, w.depth)
        return self._through(w, value)

    def _through(self, w, value) -> mi.Spectrum:
        """The walk's radiance: what it gathered before halting plus its throughput times the stylized
        value where it halted (a seam for `lookdev.record`, which keeps both per camera sample)."""
        return w.L + dr.select(w.halted, w.beta * value, 0.0)

    def stylized(self, level: int, scene, sampler, pi, si, ray, active, depth) -> mi.Spectrum:
        """g(E[L_o]) at the level-`level` vertex si, each object with its own style."""
        v = Vertex(p=si.p, n=mi.Vector3f(si.sh_frame.n), wo=-ray.d, view=mi.Vector3f(self.view),
                   depth=mi.UInt32(depth))
        styled = self._styled(si) if len(self.targets) > 1 else mi.Bool(False)
        total = mi.Spectrum(0.0)
        for target in self.targets:
            here = active & (_any_ptr(si.bsdf(), target.bsdfs, mi.BSDFPtr) if target.bsdfs else ~styled)
            total = dr.select(here, self._estimate(target.slot, level, scene, sampler, pi, si, ray, here, depth, v),
                              total)
        return total

    def _estimate(self, slot: S.StyleSlot, level, scene, sampler, pi, si, ray, active, depth, v) -> mi.Spectrum:
        style = slot.style
        if style.closed_form:
            return style.apply(mi.Color3f(0.0), v)

        def draw(carry):
            (smp,) = carry
            x = self.child(level, scene, smp, pi, si, ray, active, depth)
            if style.per_sample:
                x = style.apply(x, v)
            return x, (smp,)

        def uniform(carry):
            (smp,) = carry
            return smp.next_1d(), (smp,)

        value, _ = make_estimator(slot, level, v).run(draw, (sampler,), uniform, active, like=mi.Color3f)
        return value

    def _render_reuse(self, scene, sensor=0, seed=0, spp=0, develop=True, evaluate=True):
        """`render` with reuse=pixels: a pass is rendered by `reuse.render`, which needs every camera sample's
        neighbours at once (Mitsuba's loop calls `sample` per pass, lanes cannot see each other). It is set
        on the instance only then: a Python `render` on the class, even one calling Mitsuba's, changed how
        a render in progress takes Ctrl-C (Mitsuba's own handler took the signal and the pass ran on)."""
        from . import reuse
        sensor = scene.sensors()[sensor] if isinstance(sensor, int) else sensor
        image = reuse.render(self, scene, sensor, int(seed), int(spp) or int(sensor.sampler().sample_count()))
        return image if develop else mi.TensorXf()

    def sample(self, scene, sampler, ray, medium=None, active=True):
        self.targets = self._targets(scene)
        # emitter selection in an order of the scene's own (its emitter list changes order between runs)
        self.emitters = EmitterSampler(scene, self.settings.emitter_sampling)
        try:
            return self._sample(scene, sampler, ray, active)
        finally:
            # Keep no reference to this scene's objects once traced: Dr.Jit traces calls on every live
            # instance of a class, and a lingering BSDF or emitter of a scene that the garbage collector
            # is tearing down crashed a later trace (measured: segfault in pdf_emitter_direction).
            self.targets = []
            self.emitters = None

    def _sample(self, scene, sampler, ray, active):
        for t in self.targets:
            t.slot.style.prepare(scene)
        self.view = camera_forward(scene)
        ray = mi.Ray3f(ray)
        active = mi.Bool(active)
        # every random decision below the camera ray comes from an independent stream per lane
        sampler = LaneSampler.seeded_from(sampler, dr.width(ray.d))
        pi = scene.ray_intersect_preliminary(ray, coherent=True, active=active)
        hide = self.settings.hide_emitters
        if hide:
            ray, pi = past_area_emitters(scene, ray, pi, active)
        # alpha, as Mitsuba's `path`: the camera ray found a surface, or a visible environment
        valid = active & (pi.is_valid() | (scene.environment() is not None and not hide))
        if self.settings.stylize == "first_object_hit":
            start = active & pi.is_valid() if hide else active  # a hidden environment is black
            return self.walk(0, scene, sampler, pi, ray, start, mi.UInt32(0), halt_at_start=True), valid, []
        if self.nulls:  # the stylized vertex is the first that scatters (path.first_scattering)
            front = first_scattering(scene, sampler, pi, ray, active)
            pi, ray = front.pi, front.ray
        si = pi.compute_surface_interaction(ray, ray_flags=mi.RayFlags.All, active=active)
        hit = active & si.is_valid()
        value = self.stylized(0, scene, sampler, pi, si, ray, hit, mi.UInt32(0))
        value = dr.select(hit, value, 0.0 if hide else environment(scene, si, active))
        if self.nulls:
            value = front.beta * value
        return value, valid, []

    def aov_names(self):
        return []

    def to_string(self):
        return f"StylizedIntegrator[{self.settings.describe()}]"


MEDIA_REFUSED = ("the scene has participating media (a shape's interior/exterior medium or the sensor's), which "
                 "the 'stylized' integrator does not support yet: render it with Mitsuba's 'volpath'")


def media_problem(scene: mi.Scene) -> str | None:
    """Why `stylized` cannot render `scene` (participating media), or None."""
    return MEDIA_REFUSED if SceneGraph(scene).has_media else None
