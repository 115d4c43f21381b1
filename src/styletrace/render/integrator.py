"""`stylized`: Mitsuba integrator for the stylized rendering equation (depth-first tree sampling).

Properties (XML, Python dict, or the CLI's --set):

| name          | type   | default          | meaning |
|---------------|--------|------------------|---------|
| style         | string | identity         | registry name of the style g_theta (`styletrace styles`) |
| <param>       | any    | style default    | the style's own parameters, under their registry names |
| inner_samples | int / list | style default | n: child estimates per stylized vertex; '8,4' gives one per level |
| estimator     | string | direct           | how g(E[L]) is estimated from the n children |
| stylize       | string | first_hit        | first_hit: the camera ray's first hit; first_n_hits: the first N vertices |
| stylize_depth | int    | 1                | N for first_n_hits |
| max_depth     | int    | -1               | longest path, Mitsuba's convention (-1: unbounded) |
| rr_depth      | int    | 5                | depth at which Russian roulette starts |

The radiance leaving a stylized vertex x towards the viewer is
    L(x, wo) = g_theta( L_e(x, wo) + \\int f(x, wi, wo) L_i(x, wi) cos dwi )
(the stylized rendering equation, emission inside g). Per camera sample the integrator draws n child
estimates of the argument of g in a nested symbolic loop in the same SIMD lane (no lane replication,
so memory does not grow with n), and hands them to the estimator. Children of the last stylized level
are ordinary path-traced samples (`path.exitant`); children of earlier levels take one BSDF-sampled
bounce and recurse into the next stylized vertex. Rays that escape see the environment unstylized.
"""
from __future__ import annotations

import drjit as dr
import mitsuba as mi

from ..styles.base import Vertex, camera_forward
from .path import exitant
from .properties import Settings, props_to_dict, settings_from


def environment(scene: mi.Scene, si: mi.SurfaceInteraction3f, active: mi.Bool) -> mi.Spectrum:
    """Radiance the environment sends along an escaped ray (zero where there is none)."""
    ds = mi.DirectionSample3f(scene, si=si, ref=dr.zeros(mi.SurfaceInteraction3f))
    return ds.emitter.eval(si, active & ~si.is_valid())


def emission(scene: mi.Scene, si: mi.SurfaceInteraction3f, active: mi.Bool) -> mi.Spectrum:
    """Radiance emitted at si towards si.wi (or by the environment where si escaped)."""
    ds = mi.DirectionSample3f(scene, si=si, ref=dr.zeros(mi.SurfaceInteraction3f))
    return ds.emitter.eval(si, active)


class StylizedIntegrator(mi.SamplingIntegrator):
    def __init__(self, props: mi.Properties):
        super().__init__(props)
        self.settings: Settings = settings_from(props_to_dict(props))

    # Depth of a vertex of stylized level l along the camera path is l (the camera hit is level 0).
    def _remaining_depth(self, level: int) -> int:
        m = self.settings.max_depth
        return -1 if m < 0 else m - level

    def child(self, level: int, scene, sampler, pi, si, ray, active) -> mi.Spectrum:
        """One sample of L_e(x) + \\int f L_i at the level-`level` vertex x (`pi`/`si` along `ray`)."""
        s = self.settings
        remaining = self._remaining_depth(level)
        if level + 1 >= s.stylize_depth:
            return exitant(scene, sampler, pi, ray, active, remaining, s.rr_depth)
        # The next vertex is stylized as well: its whole exitant radiance, emission included, goes
        # through g, so it cannot be split by next-event estimation; sample the BSDF alone.
        L = emission(scene, si, active)
        if remaining == 1:
            return L
        bsdf = si.bsdf(ray)
        bs, weight = bsdf.sample(mi.BSDFContext(), si, sampler.next_1d(), sampler.next_2d(), active)
        ray2 = si.spawn_ray(si.to_world(bs.wo))
        go = active & (dr.max(weight) > 0)
        pi2 = scene.ray_intersect_preliminary(ray2, coherent=False, active=go)
        si2 = pi2.compute_surface_interaction(ray2, ray_flags=mi.RayFlags.All, active=go)
        hit = go & si2.is_valid()
        deeper = self.stylized(level + 1, scene, sampler, pi2, si2, ray2, hit)
        return L + weight * dr.select(hit, deeper, environment(scene, si2, go))

    def stylized(self, level: int, scene, sampler, pi, si, ray, active) -> mi.Spectrum:
        """g_theta(E[L_o]) at the level-`level` vertex si, estimated from child samples."""
        style = self.settings.style
        v = Vertex(p=si.p, n=mi.Vector3f(si.sh_frame.n), wo=-ray.d, view=mi.Vector3f(self.view),
                   depth=mi.UInt32(level))
        if style.closed_form:
            return dr.select(active, style.apply(mi.Color3f(0.0), v), 0.0)

        per_sample = style.per_sample

        def draw(carry):
            (smp,) = carry
            x = self.child(level, scene, smp, pi, si, ray, active)
            if per_sample:
                x = style.apply(x, v)
            return x, (smp,)

        def uniform(carry):
            (smp,) = carry
            return smp.next_1d(), (smp,)

        value, _ = self.settings.estimators[level].run(draw, (sampler,), uniform, active, v)
        return dr.select(active, value, 0.0)

    def sample(self, scene, sampler, ray, medium=None, active=True):
        self.settings.style.prepare(scene)
        self.view = camera_forward(scene)
        ray = mi.Ray3f(ray)
        active = mi.Bool(active)
        pi = scene.ray_intersect_preliminary(ray, coherent=True, active=active)
        si = pi.compute_surface_interaction(ray, ray_flags=mi.RayFlags.All, active=active)
        hit = active & si.is_valid()
        value = self.stylized(0, scene, sampler, pi, si, ray, hit)
        L = dr.select(hit, value, environment(scene, si, active))
        return L, active, []

    def aov_names(self):
        return []

    def to_string(self):
        s = self.settings
        return (f"StylizedIntegrator[style={s.style.describe()}, inner={list(s.inner)}, estimator={s.estimator}, "
                f"stylize={s.stylize}, stylize_depth={s.stylize_depth}, max_depth={s.max_depth}]")
