"""Sample reuse at the first stylized vertex (`reuse=pixels`): neighbouring camera samples pool their children.

Reference
    Tong and Hachisuka, "Practical Stylized Nonlinear Monte Carlo Rendering", SIGGRAPH 2025: path filtering,
    here restricted to the first stylized vertex, with the image as the neighbour grid (a pixel window, no
    hash grid).
    Veach and Guibas, "Optimally Combining Sampling Techniques for Monte Carlo Rendering", SIGGRAPH 1995:
    the multi-sample balance heuristic that gives the pooled samples their weights.
    Bitterli, "Correlations and Reuse for Fast and Accurate Physically Based Light Transport" (PhD thesis,
    2021), and Lin et al., "Generalized Resampled Importance Sampling", SIGGRAPH 2022: pairwise MIS.

Every camera sample i traces its ray to the first hit v_i and draws m children there (m = its style slot's
inner_samples), each split into one next-event sample (direction wl, E = L_e vis / p_light) and one BSDF
sample (direction wb, density p_i(wb), and the radiance Li arriving along it from the ordinary path kernel,
less the first emission it meets: next-event estimation has that). The pool P(v) is v and its accepted
neighbours among K drawn from the (2r+1)^2 pixel window (same sample index of the pass): same style target,
same BSDF object, shading normals with n.n' > NORMAL_MIN and camera distances within DEPTH_TOL. Then, with
v's own BSDF f_v (cosine included),

    direct(v)   = 1/(|P| m) sum_{k in P} sum_j f_v(wl_kj) E_kj                  (neighbours' visibility reused)
    indirect(v) = sum_{k in P} sum_j f_v(wb_kj) Li_kj w_k(wb_kj) / (m p_k(wb_kj))
    L(v) = g( L_e(v) + direct + indirect )

with multi-sample MIS weights w_k over the pool's BSDF-sampling techniques (`reuse_mis`):
- balance: w_k = p_k / sum_{k' in P} p_k', i.e. each sample divided by the mixture density of the whole pool;
  (K+1)^2 m density evaluations per camera sample;
- pairwise: each neighbour's technique weighed against v's only, n = |P| - 1:
  w_k = p_k / (n p_k + p_v) for a neighbour's sample, w_v = (1/n) sum_k p_v / (n p_k + p_v) for v's own;
  the weights still sum to one for every direction, at (2K+1) m evaluations.
Either is unbiased for the integral at v wherever the neighbours' incident radiance equals v's (a plane under
a uniform sky: exactly), whatever their normals, since v's own technique covers its whole hemisphere.
Dividing by the sampling neighbour's own density alone (weights='own') misses the directions a neighbour
cannot sample: the tests' negative control. g sees a mean of |P| m samples instead of m, so the Jensen bias of
direct application shrinks accordingly, at the price of the geometric mismatch between neighbours (blurred
shadow edges and style thresholds within the window; docs/reuse.md measures it).

With stylize=first_n_hits (N >= 2 levels) v is the level-0 vertex and a child is `path.bounce`'s: next-event
samples reach delta lights only, and a BSDF sample's Li is the stylized value of the level-1 vertex it reaches,
estimated for that child alone by the ordinary tree (`integrator.stylized(1, ...)`, its own n(1) children,
recursively for N > 2) or the environment where it escapes. The deeper levels are thus done first; level 0 then
pools exactly as above. With reuse_deep=world (N = 2 only) level 1 pools too, as in Tong and Hachisuka's path
filtering: all children of a batch are drawn at once (`_pooled_level1`), the level-1 vertices they reach (one
per child) draw m2 children each (`_children`: ordinary paths beyond the last level), and each pools with the
accepted ones of K2 candidates from its jittered cell of a world-space grid (world_grid.py: same target, BSDF
and normal, within distance h), with the same weights as above; g of that pooled value is the child's Li.

Light is split by technique, not by MIS, at pooling lanes: MIS weights computed at different vertices would not
sum to one at v. Lanes whose BSDF has a delta or null component, closed-form styles and escaped rays use their
own children only (the ordinary estimate, with MIS); a pool of v alone is the ordinary estimate too.
Neighbours are looked up within one pass of one crop window (`api.passes` tiles images above a million pixels;
a window is clipped at a tile's edge). The children of a pass are stored (16 floats each, side by side), so a
pass is split into batches of samples per pixel of at most BATCH_CHILDREN children.

With an adaptive count n0:n_max (`_refine`), lanes draw n0 children, pool them, and then the lanes whose pooled
mean AdaptiveDirect's rule finds too close to a style threshold (or too curved), told the pool's C = sum_P c_k
samples and their second moment, draw n_max - n0 more and recompute their pools with every member's children:
direct / C; balance with Veach's multi-sample weights with per-member counts c_k, 1 / sum_k c_k p_k; pairwise
by layers, one per child index j over the members with c_k > j, averaged with weights |P_j| / C (`_pairwise`).
"""
from __future__ import annotations

import drjit as dr
import mitsuba as mi
import numpy as np

from ..errors import SceneError
from ..estimators import channel_mean
from ..jit import no_collection
from ..styles.base import Vertex
from . import settings as S
from .acceptance import accepted
from .estimation import adaptive_direct
from .lane_sampler import LaneSampler
from .path import depth_limit, emission, environment, mis_power, past_area_emitters, walk
from .render_context import RenderContext
from .scene_graph import any_ptr
from .world_grid import WorldGrid, density_h

#: acceptance of a neighbour: shading normals within about 25 degrees, camera distances within 5 percent
NORMAL_MIN = 0.9
DEPTH_TOL = 0.05
#: children stored per batch of a pass (64 MB of child data)
BATCH_CHILDREN = 1 << 20


def window(radius: int) -> np.ndarray:
    """The (2r+1)^2 - 1 pixel offsets around a pixel (itself excluded) in a fixed shuffled order: a lane takes
    K consecutive ones from a random start, so each offset is pooled with probability K / len."""
    offsets = [(dx, dy) for dy in range(-radius, radius + 1) for dx in range(-radius, radius + 1) if dx or dy]
    order = np.random.default_rng(0x5EED).permutation(len(offsets))
    return np.array([offsets[i] for i in order], dtype=np.int32)


def batch_seed(seed: int, batch: int) -> int:
    return seed if batch == 0 else (seed * 0x9E3779B1 + batch * 0x85EBCA6B + 0x165667B1) & 0xFFFFFFFF


def render(integ, scene: mi.Scene, sensor: mi.Sensor, seed: int, spp: int, weights: str | None = None,
           keep: dict | None = None) -> mi.TensorXf:
    """The developed film of `spp` samples per pixel rendered with reuse=pixels (what `mi.render` returns).
    `weights` overrides the setting `reuse_mis` ('balance', 'pairwise'); 'own' divides each pooled BSDF sample
    by its own density (wrong: the tests' negative control);
    `keep`, a dict, receives the first batch's pools as numpy arrays (`pools`)."""
    # no scene may be finalised while a pass is recorded (jit.no_collection), and none needs collecting first
    with no_collection(), RenderContext(integ, scene):  # targets, emitters, view bound to this scene, released after
        if integ.nulls or integ.media:
            what = "participating media" if integ.media else "null-scattering surfaces (masks, null BSDFs)"
            raise SceneError(f"reuse=pixels does not support scenes with {what} yet: render with reuse=off")
        for t in integ.targets:
            if t.bsdfs:
                S.check_reusable(t.slot, f"a styled BSDF's style '{t.slot.style.name}'", integ.settings.reuse_deep)
            t.slot.style.prepare(scene)
        return _render(integ, scene, sensor, seed, spp, weights or integ.settings.reuse_mis, keep)


def _render(integ, scene, sensor, seed, spp, weights, keep):
    film = sensor.film()
    film.prepare([])
    size = film.crop_size()
    if film.sample_border():
        size += 2 * film.rfilter().border_size()
    width, height = int(size[0]), int(size[1])
    M = children_per_lane(integ.targets)
    stored = M * (1 + children_per_lane(integ.targets, 1)) if integ.settings.reuse_deep == "world" else M
    per_batch = max(1, min(spp, BATCH_CHILDREN // max(width * height * stored, 1)))
    block = film.create_block()
    done, batch = 0, 0
    while done < spp:
        n = min(per_batch, spp - done)
        value, valid, pos, wavelengths = _batch(integ, scene, sensor, batch_seed(seed, batch), n, width, height,
                                                spp, weights, keep if batch == 0 else None)
        _splat(block, film, pos, value, valid, wavelengths)
        dr.eval(block.tensor())
        done, batch = done + n, batch + 1
    film.put_block(block)
    return film.develop()


def children_per_lane(targets, level: int = 0) -> int:
    """M, the children stored per vertex of `level`: the largest count of a style slot that draws children (n_max
    for an adaptive count n0:n_max)."""
    return max([most(t.slot.n(level)) for t in targets if not t.slot.style.closed_form] or [1])


def most(n) -> int:
    """The most children a count draws: n_max of an adaptive n0:n_max, else n."""
    return int(getattr(n, "n_max", n))


def first_round(targets, level: int = 0) -> int:
    """The most children any vertex of `level` draws before the refinement round (n0 of an adaptive count)."""
    return max([int(t.slot.n(level)) for t in targets if not t.slot.style.closed_form] or [1])


def _slots(integ, si, hit, bsdf, level):
    """Per lane: its target (style slot index, -1 where none), its children count m at `level` (n0 of an
    adaptive count), whether it may pool (it draws children and its BSDF has no delta or null part)."""
    styled = integ.styled_mask(si) if len(integ.targets) > 1 else mi.Bool(False)
    target, m = mi.Int32(-1), mi.UInt32(0)
    for i, t in enumerate(integ.targets):
        here = hit & (any_ptr(si.bsdf(), t.bsdfs, mi.BSDFPtr) if t.bsdfs else ~styled)
        target = dr.select(here, i, target)
        m = dr.select(here, 0 if t.slot.style.closed_form else int(t.slot.n(level)), m)
    flags = bsdf.flags()
    pool = (m > 0) & ~mi.has_flag(flags, mi.BSDFFlags.Delta) & ~mi.has_flag(flags, mi.BSDFFlags.Null)
    return target, m, pool


def _styled_value(integ, target, x, v, fallback):
    """g of each lane's target applied to x (closed-form styles to nothing), `fallback` where no target."""
    value = mi.Spectrum(fallback)
    for i, t in enumerate(integ.targets):
        style = t.slot.style
        g = style.apply(mi.Color3f(0.0), v) if style.closed_form else style.apply(x, v)
        value = dr.select(target == i, g, value)
    return value


def _splat(block, film, pos, value, valid, wavelengths):
    alpha = dr.select(valid, mi.Float(1.0), mi.Float(0.0))
    if dr.all(mi.has_flag(film.flags(), mi.FilmFlags.Special)):
        block.put(pos, film.prepare_sample(value, wavelengths, block.channel_count(), weight=1.0, alpha=alpha))
    elif mi.has_flag(film.flags(), mi.FilmFlags.Alpha):
        block.put(pos, [value.x, value.y, value.z, alpha, mi.Float(1.0)])
    else:
        block.put(pos, [value.x, value.y, value.z, mi.Float(1.0)])


def _camera(sensor, sampler, width, height, spp, spp_total):
    """Camera rays as Mitsuba's SamplingIntegrator::render makes them: lane = pixel * spp + sample index."""
    film = sensor.film()
    N = width * height * spp
    idx = dr.arange(mi.UInt32, N) // spp
    y = idx // width
    pos = mi.Vector2i(mi.Int32(idx - y * width), mi.Int32(y))
    if film.sample_border():
        pos -= mi.Vector2i(film.rfilter().border_size())
    pos += mi.Vector2i(film.crop_offset())
    pos_f = mi.Vector2f(pos) + sampler.next_2d()
    scale = dr.rcp(mi.ScalarVector2f(film.crop_size()))
    adjusted = dr.fma(pos_f, scale, -mi.ScalarVector2f(film.crop_offset()) * scale)
    aperture = sampler.next_2d() if sensor.needs_aperture_sample() else mi.Point2f(0.5)
    time = mi.Float(sensor.shutter_open())
    if sensor.shutter_open_time() > 0:
        time += sampler.next_1d() * sensor.shutter_open_time()
    ray, weight = sensor.sample_ray_differential(time, 0.0, adjusted, aperture)
    if ray.has_differentials:
        ray.scale_differential(dr.rsqrt(spp_total))
    return ray, weight, pos_f


def _batch(integ, scene, sensor, seed, spp, width, height, spp_total, weights, keep=None):
    s = integ.settings
    N = width * height * spp
    sampler = sensor.sampler().clone()
    sampler.set_sample_count(spp)
    sampler.set_samples_per_wavefront(spp)
    sampler.seed(seed, N)
    ray, ray_weight, pos = _camera(sensor, sampler, width, height, spp, spp_total)
    ray = mi.Ray3f(ray)
    origin = mi.Point3f(ray.o)
    lanes = LaneSampler.seeded_from(sampler, N)
    pi = scene.ray_intersect_preliminary(ray, coherent=True)
    if s.hide_emitters:
        ray, pi = past_area_emitters(scene, ray, pi, mi.Bool(True))
    valid = pi.is_valid() | (scene.environment() is not None and not s.hide_emitters)
    si = pi.compute_surface_interaction(ray, ray_flags=mi.RayFlags.All)
    hit = si.is_valid()
    bsdf = si.bsdf(ray)

    # which target (style slot) each lane belongs to, its children count m, and whether it may pool
    targets = integ.targets
    target, m, pool = _slots(integ, si, hit, bsdf, 0)
    M = children_per_lane(targets)
    refine = [i for i, t in enumerate(targets) if most(t.slot.n(0)) > int(t.slot.n(0))]

    # the children, stored per lane: child j of lane i at i * M + j
    kids = Children(N * M)
    base = dr.select(hit, emission(scene, si, hit), 0.0 if s.hide_emitters else environment(scene, si, ~hit))
    lane = dr.arange(mi.UInt32, N)
    if s.reuse_deep == "world":
        own = _pooled_level1(integ, scene, lanes, si, bsdf, hit & (m > 0), m, M, kids, weights, keep)
    else:
        own = _children(integ, scene, lanes, si, bsdf, hit & (m > 0), pool, mi.UInt32(0), m, first_round(targets),
                        M, kids, lane)
    W = (2 * s.reuse_radius + 1) ** 2 - 1
    K = min(s.reuse_k, W)  # settings.parse keeps K <= MAX_REUSE_K
    start = mi.UInt32(dr.minimum(lanes.next_1d() * W, W - 1)) if K < W else dr.zeros(mi.UInt32, N)
    depth = dr.norm(si.p - origin)
    # the refinement round seeds its children from the lanes' generators: evaluated with the first round's
    # children, or reading them would trace the first round again
    dr.eval(kids, own, base, si, target, m, pool, depth, start, bsdf, valid, ray_weight, pos, lanes if refine else ())

    grid = Grid(width, height, spp, s.reuse_radius, K, start)
    mask = grid.accepted(target, bsdf, pool, mi.Vector3f(si.sh_frame.n), depth)
    dr.eval(mask)
    if keep is not None:
        keep.update(mask=np.asarray(mask, dtype=np.uint64), start=np.asarray(start, dtype=np.int64), spp=spp,
                    width=width, height=height, K=K, radius=s.reuse_radius, target=np.asarray(target))
    v = Vertex(p=si.p, n=mi.Vector3f(si.sh_frame.n), wo=-ray.d, view=mi.Vector3f(integ.view), depth=mi.UInt32(0))
    count = m
    if refine:
        mean, s1, s2, C = _pooled(grid, mask, si, bsdf, m, first_round(targets), M, kids, weights, moments=True)
        mean, count = _refine(integ, scene, lanes, grid, mask, si, bsdf, target, pool, m, M, kids, weights, v,
                              refine, base, mean, s1, s2, C, keep)
    else:
        mean = _pooled(grid, mask, si, bsdf, m, first_round(targets), M, kids, weights)
    mean = dr.select(pool, mean, own / mi.Float(dr.maximum(m, 1)))
    x = base + mean
    if keep is not None:  # what g sees, the children each lane pooled as its own, and those it stored
        stored = np.asarray(dr.squared_norm(kids.directions()) > 0).reshape(N, M).sum(axis=1)
        keep.update(x=np.asarray(x), children=np.asarray(count), stored=stored)
    value = _styled_value(integ, target, x, v, base)
    return value * ray_weight, valid, pos, ray.wavelengths


def _refine(integ, scene, lanes, grid, mask, si, bsdf, target, pool, m, M, kids, weights, v, refine, base, mean,
            s1, s2, C, keep):
    """The refinement round of adaptive counts n0:n_max: the pooling lanes whose pooled mean the style's rule
    (estimators.AdaptiveDirect.needs_more, told the pool's |P| n0 samples and their moments) finds too close
    to a threshold, or too curved, draw n_max - n0 more children (those lanes alone, compacted), and recompute
    their pools with every member's children. mean, s1, s2 and C: the first round's pooled mean, moments and
    count (`_pooled`). Returns (pooled mean, children per lane)."""
    s = integ.settings
    dr.eval(mean, s1, s2, C)  # one kernel for the first round's pool (each output traced alone re-runs the loop)
    x = base + mean
    state = {"count": C, "sum": x * C, "mean_u": channel_mean(x),
             "m2_u": dr.maximum(s2 - dr.square(s1) / dr.maximum(C, 1.0), 0.0)}
    flag, n_max = mi.Bool(False), mi.UInt32(m)
    for i in refine:
        slot = integ.targets[i].slot
        est = adaptive_direct(slot.style, int(slot.n(0)), most(slot.n(0)), v, s.adaptive_z, s.adaptive_bias)
        state["tau"] = tuple(dr.zeros(mi.Float, dr.width(C)) + t for t in est.thresholds)
        here = (target == i) & pool
        flag |= here & est.needs_more(state)
        n_max = dr.select(here, most(slot.n(0)), n_max)
    dr.eval(flag, n_max)
    idx = dr.compress(flag)
    count = dr.select(flag, n_max, m)
    if keep is not None:
        keep.update(flag=np.asarray(flag), mean_u=np.asarray(state["mean_u"]), m2_u=np.asarray(state["m2_u"]),
                    count=np.asarray(C))
    if dr.width(idx) == 0:
        return mean, count
    # the extra children, one lane each (flagged lane x extra child: wide and loop-free), each on its own
    # random stream: the flagged lane's state, a stream index per extra child
    more = max(most(integ.targets[i].slot.n(0)) - int(integ.targets[i].slot.n(0)) for i in refine)
    f = dr.arange(mi.UInt32, dr.width(idx) * more)
    at = dr.gather(mi.UInt32, idx, f // more)
    sub = LaneSampler(mi.PCG32(dr.width(f), initstate=dr.gather(mi.UInt64, lanes.rng.state, at),
                               initseq=mi.UInt64(f)))
    _children(integ, scene, sub, dr.gather(mi.SurfaceInteraction3f, si, at), dr.gather(mi.BSDFPtr, bsdf, at),
              mi.Bool(True), mi.Bool(True), dr.gather(mi.UInt32, m, at) + f % more, dr.gather(mi.UInt32, n_max, at),
              1, M, kids, at)
    si_k, bsdf_k = dr.gather(mi.SurfaceInteraction3f, si, idx), dr.gather(mi.BSDFPtr, bsdf, idx)
    dr.eval(kids, count)
    sub_grid = Grid(grid.width, grid.height, grid.spp, grid.radius, grid.K, dr.gather(mi.UInt32, grid.start, idx),
                    lane=idx)
    again = _pooled(sub_grid, dr.gather(mi.UInt64, mask, idx), si_k, bsdf_k, count, M, M, kids, weights,
                    si_all=si, equal=False)
    mean = mi.Spectrum(mean)
    dr.eval(mean)
    dr.scatter(mean, again, idx)
    return mean, count


def pools(keep: dict) -> list[list[tuple[int, int]]]:
    """From `render(..., keep=d)`: per lane, the (x, y) pixels of its pool, itself first (tests, docs)."""
    offsets = window(keep["radius"])
    W, spp, width = len(offsets), keep["spp"], keep["width"]
    out = []
    for lane, (mask, start) in enumerate(zip(keep["mask"], keep["start"])):
        pix = lane // spp
        x, y = pix % width, pix // width
        members = []
        for q in range(keep["K"] + 1):
            if int(mask) >> q & 1:
                dx, dy = (0, 0) if q == 0 else offsets[(int(start) + q - 1) % W]
                members.append((int(x + dx), int(y + dy)))
        out.append(members)
    return out


class Children:
    """The stored children (see the module docstring), 16 floats each, side by side in one flat array: a child
    is read with four 4-float loads instead of 16 scattered gathers (the pool reads every child K + 1 times).
    Layout: wl, E, wb, pdf, Li, and fLi = f_i(wb) Li at the child's own vertex (pairwise's own samples)."""
    DRJIT_STRUCT = {"data": mi.Float}
    SIZE = 16

    def __init__(self, size: int = 0):
        self.data = dr.zeros(mi.Float, size * self.SIZE)

    def store(self, c, wl, E, wb, pdf, Li, fLi, active):
        packets = (mi.Vector4f(wl.x, wl.y, wl.z, E[0]), mi.Vector4f(E[1], E[2], wb.x, wb.y),
                   mi.Vector4f(wb.z, pdf, Li[0], Li[1]), mi.Vector4f(Li[2], fLi[0], fLi[1], fLi[2]))
        for t, value in enumerate(packets):
            dr.scatter(self.data, value, c * 4 + t, active)

    def load(self, c, active):
        """(wl, E, wb, pdf, Li, fLi) of the children at flat indices c."""
        a, b, d, e = (dr.gather(mi.Vector4f, self.data, c * 4 + t, active) for t in range(4))
        return (mi.Vector3f(a.x, a.y, a.z), mi.Spectrum(a.w, b.x, b.y), mi.Vector3f(b.z, b.w, d.x), d.y,
                mi.Spectrum(d.z, d.w, e.x), mi.Spectrum(e.y, e.z, e.w))

    def directions(self):
        """wl of every stored child (zero where none was stored)."""
        first = dr.arange(mi.UInt32, dr.width(self.data) // self.SIZE) * self.SIZE
        return mi.Vector3f(*(dr.gather(mi.Float, self.data, first + k) for k in range(3)))


class _Draw:
    """One child's two samples at the vertex si (its lane `on`): a next-event sample (direction ds.d, E) and a
    BSDF sample (direction wb, density bs.pdf, weight w_b) with the ray to what it reaches (ray2, pi2). At a
    non-last level of first_n_hits (`nested`) next-event estimation samples delta lights only, as
    `path.bounce`: the BSDF sample reaches every other emitter, which the next level stylizes."""

    def __init__(self, integ, scene, smp, si, bsdf, on, pool, depth, nested):
        step = on & (depth + 1 < depth_limit(integ.settings.max_depth))
        to_light = step & mi.has_flag(bsdf.flags(), mi.BSDFFlags.Smooth)
        ds, em_weight = integ.emitters.sample_direction(si, smp.next_2d(), to_light)
        to_light &= ds.pdf != 0.0
        if nested:
            to_light &= ds.delta
        val, pdf_l, bs, w_b = bsdf.eval_pdf_sample(mi.BSDFContext(), si, si.to_local(ds.d), smp.next_1d(),
                                                   smp.next_2d(), step)
        # Lanes that pool split the light by technique, not by MIS: next-event estimation takes all the
        # emission it can reach (weight 1) and the BSDF sample none of the first emission it meets (pdf 0
        # below), so the two pooled sums are each unbiased whatever the neighbours' densities; MIS weights
        # computed at different vertices would not add up to one. (first_n_hits splits them so already.)
        w_nee = dr.select(ds.delta | pool, 1.0, mis_power(ds.pdf, pdf_l))
        self.to_light, self.val, self.ds, self.bs, self.w_b = to_light, val, ds, bs, w_b
        self.E = dr.select(to_light, em_weight * w_nee, 0.0)
        self.wb = si.to_world(bs.wo)
        self.go = step & (dr.max(w_b) > 0)
        self.ray2 = si.spawn_ray(self.wb)
        self.pi2 = scene.ray_intersect_preliminary(self.ray2, coherent=False, active=self.go)

    def next_vertex(self):
        """(si2, hit2): the surface the BSDF sample reaches, where it reaches one."""
        si2 = self.pi2.compute_surface_interaction(self.ray2, ray_flags=mi.RayFlags.All, active=self.go)
        return si2, self.go & si2.is_valid()

    def seen(self, scene, si2, hit2, value):
        """The radiance Li along the BSDF sample: `value` where it hit a surface, else the environment."""
        return dr.select(self.go, dr.select(hit2, value, environment(scene, si2, self.go)), 0.0)

    def store(self, kids, at, Li, on):
        """Store the child at flat index `at` with its Li; its ordinary estimate x (0 where not `on` or not
        finite)."""
        go, bs = self.go, self.bs
        x = dr.select(self.to_light, self.val * self.E, 0.0) + dr.select(go, self.w_b * Li, 0.0)
        ok = on & dr.all(dr.isfinite(x))
        kids.store(at, self.ds.d, self.E, self.wb, dr.select(go, bs.pdf, 0.0), Li,
                   dr.select(go, self.w_b * bs.pdf * Li, 0.0), ok)
        return dr.select(ok, x, 0.0)


def _children(integ, scene, lanes, si, bsdf, active, pool, first, last, J, M, kids, lane, depth: int = 0):
    """Draw children first .. last - 1 of each lane (at most J of them) at its vertex (the first hit, or with
    `depth` 1 a second-level vertex whose children are ordinary paths), store them at lane * M + j, and return
    the sum of their ordinary estimates (next-event plus BSDF-sampled radiance, emission at v left out)."""
    s = integ.settings
    nested = s.stylize == "first_n_hits" and s.stylize_depth > depth + 1

    def body(i, smp, total):
        j = first + i
        on = active & (j < last)
        c = _Draw(integ, scene, smp, si, bsdf, on, pool, depth, nested)
        if nested:  # the level-1 vertex, stylized by the ordinary tree (deeper levels first), or the sky
            si2, hit2 = c.next_vertex()
            Li = c.seen(scene, si2, hit2, integ.stylized(depth + 1, scene, smp, c.pi2, si2, c.ray2, hit2,
                                                          mi.UInt32(depth + 1)))
        else:
            delta = mi.has_flag(c.bs.sampled_type, mi.BSDFFlags.Delta)
            w = walk(scene, smp, c.pi2, c.ray2, c.go, s.max_depth, s.rr_depth, depth + 1, emitters=integ.emitters,
                     came_from=(dr.detach(si, True), dr.select(pool, 0.0, c.bs.pdf), delta & ~pool))
            Li = dr.select(c.go, w.L, 0.0)
        return i + 1, smp, total + c.store(kids, lane * M + j, Li, on)

    _, lanes_out, total = dr.while_loop((mi.UInt32(0), lanes, mi.Spectrum(0.0)), lambda i, smp, t: i < J, body,
                                        label="styletrace reuse children")
    lanes.rng = lanes_out.rng
    return total


def _pooled_level1(integ, scene, lanes, si, bsdf, active, m, M, kids, weights, keep=None):
    """reuse_deep=world: `_children` for first_n_hits at depth 2 with the second level pooled too. All children
    of a batch are drawn at once, one lane each (child j of lane i at i * M + j): a delta-light sample and a BSDF
    sample from the first hit, as `path.bounce`; the second-level vertices they reach are shaded together by
    `_level2`, whose value is the child's Li. Stores the children in `kids`; returns each lane's sum of their
    ordinary estimates."""
    N = dr.width(si.p)
    idx = dr.arange(mi.UInt32, N * M)
    owner, j = idx // M, idx % M
    on = dr.gather(mi.Bool, active, owner) & (j < dr.gather(mi.UInt32, m, owner))
    # one PCG32 stream per child, seeded from its camera sample's own stream
    hi = dr.gather(mi.UInt32, dr.reinterpret_array(mi.UInt32, lanes.next_1d()), owner)
    lo = dr.gather(mi.UInt32, dr.reinterpret_array(mi.UInt32, lanes.next_1d()), owner)
    smp = LaneSampler(mi.PCG32(N * M, initstate=(mi.UInt64(hi) << 32) | mi.UInt64(lo),
                               initseq=dr.arange(mi.UInt64, N * M)))
    c = _Draw(integ, scene, smp, dr.gather(mi.SurfaceInteraction3f, si, owner), dr.gather(mi.BSDFPtr, bsdf, owner),
              on, mi.Bool(True), 0, nested=True)
    si2, hit2 = c.next_vertex()
    x = c.store(kids, idx, c.seen(scene, si2, hit2, _level2(integ, scene, smp, si2, c.ray2, hit2, weights, keep)), on)
    lane = dr.arange(mi.UInt32, N)
    total = mi.Spectrum(0.0)
    for k in range(M):  # in a fixed order (a scatter-add would not be bit-reproducible)
        total += dr.gather(mi.Spectrum, x, lane * M + k)
    return total


def _level2(integ, scene, smp, si, ray, hit, weights, keep=None):
    """The stylized value of second-level vertices `si` (reached along `ray`; `hit`: a surface) that pool the
    children of their world-space neighbours (world_grid.py): m2 children each by `_children` (ordinary
    paths beyond the last stylized level), pooled exactly as at the first hit, then g of the vertex's slot."""
    s = integ.settings
    bsdf = si.bsdf(ray)
    target, m, pool = _slots(integ, si, hit, bsdf, 1)
    M = children_per_lane(integ.targets, 1)
    kids = Children(dr.width(si.p) * M)
    base = emission(scene, si, hit)
    J = first_round(integ.targets, 1)
    own = _children(integ, scene, smp, si, bsdf, hit & (m > 0), pool, mi.UInt32(0), m, J, M, kids,
                    dr.arange(mi.UInt32, dr.width(si.p)), depth=1)
    jitter, start = mi.Point3f(smp.next_1d(), smp.next_1d(), smp.next_1d()), smp.next_1d()
    n = mi.Vector3f(si.sh_frame.n)
    dr.eval(kids, own, base, si, target, m, pool, jitter, start, bsdf, smp)
    box = scene.bbox()
    diag = float(dr.norm(box.extents()))
    h = s.reuse_h * diag if s.reuse_h > 0 else density_h(si.p, pool, s.reuse_k2, box.min, S.MIN_REUSE_H * diag, diag)
    grid = WorldGrid(si.p, pool, h, s.reuse_k2, jitter, start, box.min)
    mask = grid.accepted(target, bsdf, pool, n, NORMAL_MIN)
    dr.eval(mask)
    if keep is not None:
        keep.update(world_mask=np.asarray(mask, dtype=np.uint64), world_p=np.asarray(si.p, dtype=np.float64),
                    world_pool=np.asarray(pool, dtype=bool), world_h=grid.h, world_k=grid.K,
                    world_order=np.asarray(grid.order), world_first=np.asarray(grid.first),
                    world_count=np.asarray(grid.count), world_offset=np.asarray(grid.offset))
    mean = _pooled(grid, mask, si, bsdf, m, J, M, kids, weights)
    mean = dr.select(pool, mean, own / mi.Float(dr.maximum(m, 1)))
    v = Vertex(p=si.p, n=n, wo=-ray.d, view=mi.Vector3f(integ.view), depth=mi.UInt32(1))
    return _styled_value(integ, target, base + mean, v, 0.0)


class Grid:
    """The neighbour slots of each lane: slot 0 is the lane itself, slot q >= 1 the pixel at window offset
    order[(start + q - 1) mod W], same sample index. `lane`: the lanes (indices into the pass) this grid
    serves, all of them by default, with `start` given per served lane."""

    def __init__(self, width, height, spp, radius, K, start, lane=None):
        self.width, self.height, self.spp, self.K, self.radius = width, height, spp, K, radius
        offsets = window(radius)
        self.W = len(offsets)
        self.dx, self.dy = mi.Int32(offsets[:, 0]), mi.Int32(offsets[:, 1])
        self.start = start
        self.lane = dr.arange(mi.UInt32, width * height * spp) if lane is None else lane
        pix = self.lane // spp
        self.s = self.lane - pix * spp
        self.y = mi.Int32(pix // width)
        self.x = mi.Int32(pix) - self.y * width

    def neighbour(self, q):
        """(lane index, inside the image) of slot q (a UInt32 array)."""
        o = (self.start + q - 1) % self.W
        first = q == 0
        x = self.x + dr.select(first, 0, dr.gather(mi.Int32, self.dx, o, ~first))
        y = self.y + dr.select(first, 0, dr.gather(mi.Int32, self.dy, o, ~first))
        inside = (x >= 0) & (x < self.width) & (y >= 0) & (y < self.height)
        at = (mi.UInt32(dr.maximum(y, 0)) * self.width + mi.UInt32(dr.maximum(x, 0))) * self.spp + self.s
        return dr.select(inside, at, self.lane), inside

    def accepted(self, target, bsdf, pool, n, depth) -> mi.UInt64:
        """Bit q set where slot q's vertex may be pooled with the lane's own (acceptance.py; camera distances
        within DEPTH_TOL)."""
        def near(at, ok):
            return dr.abs(dr.gather(mi.Float, depth, at, ok) - depth) <= DEPTH_TOL * depth
        return accepted(self.neighbour, self.K, target, bsdf, pool, n, NORMAL_MIN, near, "styletrace reuse accept")


def _has(mask, q):
    """Whether pool slot q (a UInt32 array) is a member: its bit in the pool's mask."""
    return ((mask >> mi.UInt64(q)) & mi.UInt64(1)) != 0


def _pool_count(grid, mask, count):
    """C = sum over the pool's members of their children counts (count: per lane of the pass)."""
    def body(q, total):
        here = _has(mask, q)
        at, _ = grid.neighbour(q)
        return q + 1, total + dr.select(here, dr.gather(mi.UInt32, count, at, here), 0)
    _, total = dr.while_loop((mi.UInt32(0), mi.UInt32(0)), lambda q, t: q <= grid.K, body,
                             label="styletrace reuse pool count")
    return total


def _total(grid, mask, count, equal):
    """C = sum over the pool's members of their children counts: |P| c_v where all members have v's count."""
    if equal:
        return mi.Float(dr.popcnt(mask)) * mi.Float(dr.gather(mi.UInt32, count, grid.lane))
    return mi.Float(_pool_count(grid, mask, count))


def _counts(grid, mask, count, equal):
    """(c_v, C, member_count): v's own children count, C = sum over the pool of c_k, and c_k of the members at
    lanes `at` (v's own where all members have it: `equal`)."""
    cv = mi.Float(dr.gather(mi.UInt32, count, grid.lane))

    def member_count(at, on):
        return cv if equal else mi.Float(dr.gather(mi.UInt32, count, at, on))
    return cv, _total(grid, mask, count, equal), member_count


def _pooled(grid, mask, si, bsdf, count, J, M, kids, weights, moments=False, si_all=None, equal=True):
    """(direct + indirect)(v) of the module docstring for every lane the grid serves (meaningful where the lane
    pools); si, bsdf and mask are those lanes', si_all (default si) and `count` every lane's of the pass (member
    k contributes its first c_k = count_k children, at most J). With `moments`, also the first two moments of
    the per-child estimates' brightness, sum_i u_i and sum_i u_i^2, u_i = C x_i (x_i child i's terms of the
    sums, C = sum_P c_k), which give the pooled mean's sample variance, and C. `equal`: every member has v's
    count (the first round: members share v's style slot), so C = |P| c_v without a loop over the slots."""
    if weights == "pairwise":
        return _pairwise(grid, mask, si, bsdf, count, J, M, kids, moments, si_all, equal)
    ctx = mi.BSDFContext()
    K = grid.K
    si_all = si if si_all is None else si_all
    active = mask != 0
    cv, C, member_count = _counts(grid, mask, count, equal)

    def has(q):
        return active & _has(mask, q)

    def mixture(wb, on):
        """sum over pool members q of c_q p_q(wb), p_q at member q's own vertex (v's BSDF object: accepted
        members share it): a loop over the K + 1 slots."""
        def body(q, total):
            here = on & has(q)
            at, _ = grid.neighbour(q)
            sk = dr.gather(mi.SurfaceInteraction3f, si_all, at, here)
            p = bsdf.pdf(ctx, sk, sk.to_local(wb), here)
            total += dr.select(here, member_count(at, here) * p, 0.0)
            return q + 1, total
        _, total = dr.while_loop((mi.UInt32(0), mi.Float(0.0)), lambda q, t: on & (q <= K), body,
                                 label="styletrace reuse densities")
        return total

    def body(i, direct, indirect, s1, s2):
        q, j = i // J, i % J
        at, _ = grid.neighbour(q)
        on = has(q) & (j < member_count(at, has(q)))
        wl, E, wb, pdf, Li, _ = kids.load(at * M + j, on)
        d = dr.select(on, bsdf.eval(ctx, si, si.to_local(wl), on) * E, 0.0)
        take = on & (pdf > 0)
        f = bsdf.eval(ctx, si, si.to_local(wb), take) * Li
        if weights == "balance":    # f Li / sum_P c_k p_k
            w = dr.rcp(mixture(wb, take))
        else:                       # 'own': f Li / p_k, averaged over the C samples (wrong: the negative control)
            w = dr.rcp(pdf * C)
        b = dr.select(take & dr.isfinite(w) & (w > 0), f * w, 0.0)
        direct, indirect = direct + d, indirect + b
        if moments:
            s1, s2 = _moments(s1, s2, on, d + b * C)
        return i + 1, direct, indirect, s1, s2

    _, direct, indirect, s1, s2 = dr.while_loop(
        (mi.UInt32(0), mi.Spectrum(0.0), mi.Spectrum(0.0), mi.Float(0.0), mi.Float(0.0)),
        lambda i, d, ind, a, b: i < (K + 1) * J, body, label="styletrace reuse pool")
    mean = direct / dr.maximum(C, 1.0) + indirect
    return (mean, s1, s2, C) if moments else mean


def _moments(s1, s2, on, y):
    """The running sums of u and u^2, u the brightness (channel mean) of a child's estimate y, where `on`."""
    u = channel_mean(y)
    return s1 + dr.select(on, u, 0.0), s2 + dr.select(on, dr.square(u), 0.0)


def _layer(grid, mask, count, j, active):
    """The pool members with more than j children (their slot bits; slot 0, v itself, where c_v > j)."""
    def body(q, bits):
        here = active & _has(mask, q)
        at, _ = grid.neighbour(q)
        deep = here & (dr.gather(mi.UInt32, count, at, here) > j)
        return q + 1, bits | dr.select(deep, mi.UInt64(1) << mi.UInt64(q), mi.UInt64(0))
    _, bits = dr.while_loop((mi.UInt32(0), mi.UInt64(0)), lambda q, b: q <= grid.K, body,
                            label="styletrace reuse layer")
    return bits


def _pairwise(grid, mask, si, bsdf, count, J, M, kids, moments, si_all, equal):
    """_pooled with pairwise weights, n = |P| - 1 (counts c_k: Veach's multi-sample form of each pair):
        a member k's sample:  f_v Li / (n c_k p_k + c_v p_v)
        v's own sample:       f_v Li (1/n) sum_{k != v} 1 / (n c_k p_k + c_v p_v)
    (for equal counts m: w_k = p_k / (n p_k + p_v) and w_v = (1/n) sum_k p_v / (n p_k + p_v), over m samples).
    Per child index j, one loop over the members k != v gives both v's terms for k's child j and k's term of
    the canonical sum of v's own child j; v's own child's f_v Li was stored when it was drawn.

    Unequal counts (the refinement round's pools): child index j is a layer, P_j the members with c_k > j, each
    layer pooled with pairwise weights over its own members (n_j = |P_j| - 1, one sample per technique) and
    the layers averaged with weights |P_j| / C (each layer is unbiased where the pool's is, and the weights sum
    to one). With equal counts this is the formula above; with unequal ones a layer beyond the first round's n0
    holds only the refined members, so its loop visits those alone (the set bits of P_j), where the counts'
    weights would need every member's density for each of v's n_max children."""
    ctx = mi.BSDFContext()
    K = grid.K
    si_all = si if si_all is None else si_all
    active = mask != 0
    cv, C, member_count = _counts(grid, mask, count, equal)

    others = mi.Float(dr.popcnt(mask)) - 1.0                  # n = |P| - 1
    alone = others < 0.5
    own = grid.lane * M

    def index(j, direct, indirect, s1, s2):
        mine = active & (j < cv)
        wl, E, wv, pv, _, fLi = kids.load(own + j, mine)
        if equal:
            n_j, alone_j, scale = others, alone, None
        else:  # layer j: its members, their number less one, and its weight |P_j| / C
            layer = _layer(grid, mask, count, j, active)
            n_j = mi.Float(dr.popcnt(layer)) - 1.0
            alone_j, scale = n_j < 0.5, (n_j + 1.0) / dr.maximum(C, 1.0)
        theirs = mine & (pv > 0) & ~alone_j

        def term(q, here, direct, indirect, s1, s2, canonical):
            at, _ = grid.neighbour(q)
            ck = member_count(at, here)
            on = here & (j < ck)
            wl, E, wb, pdf, Li, _ = kids.load(at * M + j, on)
            d = dr.select(on, bsdf.eval(ctx, si, si.to_local(wl), on) * E, 0.0)
            take = on & (pdf > 0)
            f, p_v = bsdf.eval_pdf(ctx, si, si.to_local(wb), take)
            w = dr.rcp(others * ck * pdf + cv * p_v) if equal else scale * dr.rcp(n_j * pdf + p_v)
            b = dr.select(take & dr.isfinite(w) & (w > 0), f * Li * w, 0.0)
            if moments:
                s1, s2 = _moments(s1, s2, on, d + b * C)
            # v's own child j against member k's technique, at k's vertex
            there = here & theirs
            sk = dr.gather(mi.SurfaceInteraction3f, si_all, at, there)
            p_k = bsdf.pdf(ctx, sk, sk.to_local(wv), there)
            canonical += dr.select(there, dr.rcp(others * ck * p_k + cv * pv) if equal else dr.rcp(n_j * p_k + pv),
                                   0.0)
            return direct + d, indirect + b, s1, s2, canonical

        if equal:  # every slot q = 1 .. K
            def member(q, *acc):
                here = active & _has(mask, q)
                return q + 1, *term(q, here, *acc)
            _, direct, indirect, s1, s2, canonical = dr.while_loop(
                (mi.UInt32(1), direct, indirect, s1, s2, mi.Float(0.0)), lambda q, *_: q <= K, member,
                label="styletrace reuse pool members")
        else:      # the layer's members k != v alone: its set bits, lowest first
            def member(bits, *acc):
                q = mi.UInt32(dr.tzcnt(bits))
                return bits & (bits - mi.UInt64(1)), *term(q, bits != 0, *acc)
            _, direct, indirect, s1, s2, canonical = dr.while_loop(
                (layer & ~mi.UInt64(1), direct, indirect, s1, s2, mi.Float(0.0)), lambda bits, *_: bits != 0,
                member, label="styletrace reuse pool layer")
        d = dr.select(mine, bsdf.eval(ctx, si, si.to_local(wl), mine) * E, 0.0)
        if equal:
            w = dr.select(alone, dr.rcp(cv * pv), canonical / others)
        else:
            w = scale * dr.select(alone_j, dr.rcp(pv), canonical / n_j)
        b = dr.select(mine & (pv > 0) & dr.isfinite(w) & (w > 0), fLi * w, 0.0)
        if moments:
            s1, s2 = _moments(s1, s2, mine, d + b * C)
        return j + 1, direct + d, indirect + b, s1, s2

    zero = (mi.Spectrum(0.0), mi.Spectrum(0.0), mi.Float(0.0), mi.Float(0.0))
    _, direct, indirect, s1, s2 = dr.while_loop((mi.UInt32(0), *zero), lambda j, *_: j < J, index,
                                                label="styletrace reuse pool")
    mean = direct / dr.maximum(C, 1.0) + indirect
    return (mean, s1, s2, C) if moments else mean
