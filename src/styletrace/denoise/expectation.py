"""Denoising the expectation before the style: `--denoise expectation`.

    image, buf = render_denoised_expectation(Shot(scene, integrator, spp=16, seed=0))

Per camera sample the renderer records the stylized vertex, the radiance before it and the mean of
its children (`lookdev.record`). Per pixel M averages those means, less each sample's own emission
(`expectation`); OIDN denoises M with the guides into D (`attach`), and every camera sample takes
its own slot's g of D interpolated at its own film position (`at_samples`), or with coverage g is
evaluated at k stratified points per pixel (`coverage`). D at the samples is kept in the buffer
(`DENOISED`), so a restyle styles D too. Supported and refused:
`pipeline.denoising.expectation_refusal`.
Design: docs/design/expectation_denoising.md.
"""
from __future__ import annotations

import copy
from dataclasses import dataclass, replace
from typing import Any, Callable, Iterator

import numpy as np

from styletrace.denoise import coverage as coverage_module
from styletrace.denoise import oidn
from styletrace.denoise.probe import Probe
from styletrace.denoise.temporal import box3
from styletrace.errors import UsageError
from styletrace.gate import dr, mi
from styletrace.host_arrays import aligned
from styletrace.kernel import guides
from styletrace.kernel.integrator import StylizedIntegrator
from styletrace.lookdev.buffer import DENOISED, MAX_CAMERA_SAMPLES, SPREAD, Buffer
from styletrace.lookdev.record import record, scene_label
from styletrace.lookdev.restyle import (
    accumulate,
    field,
    joined,
    prepare_slots,
    sample_values,
    slots_for,
)
from styletrace.pipeline.denoising import Denoising, check_expectation
from styletrace.pipeline.passes import PassSplit, Progress, Shot, pass_seed
from styletrace.scene.defaults import ScenePilot


def expectation(buf: Buffer, emission=None) -> np.ndarray:
    """M: per pixel, the mean of its camera samples' children means where a stylized vertex was
    found (0 where none was).

    Args:
        buf: the buffer of means. emission: each sample's own emitted radiance (N x 3 or a
            mi.Color3f, `own_surface`, `own_on_device`), taken off first (M is then the reflected
            part alone), or None.

    Returns:
        M, H x W x 3 float32.
    """
    return _expectation(buf, _reflected(buf, emission))


def _expectation(buf: Buffer, refl: np.ndarray) -> np.ndarray:
    """M of the samples' reflected parts (3 x N, `_reflected`)."""
    return _sample_moments(buf, refl)[1].T.reshape(buf.height, buf.width, 3).astype(np.float32)


def reflected(buf: Buffer, emission) -> np.ndarray:
    """Each camera sample's children mean, less its own emission where given.

    Args:
        buf: the buffer of means. emission: N x 3 or a mi.Color3f, or None.

    Returns:
        N x 3 float64.
    """
    return _reflected(buf, emission).T


def _reflected(buf: Buffer, emission) -> np.ndarray:
    """`reflected` as 3 x N (each channel's samples next to each other, as bincount reads them)."""
    mean = buf.arrays["mean"].astype(np.float64)
    if emission is None:
        return mean
    return mean - (emission.T if isinstance(emission, np.ndarray) else np.asarray(emission))


def _sample_moments(buf: Buffer, values: np.ndarray, found: np.ndarray | None = None):
    """Per pixel, over its samples with a stylized vertex (or those of `found`) of `values` (C x N):
    (count, mean, variance of the mean = (mean of squares - squared mean) / (count - 1)); mean 0
    where a pixel has no such sample, variance NaN below 2. Float64, flat over the pixels (H*W, and
    C x H*W)."""
    a = buf.arrays
    found = a["slot"] >= 0 if found is None else found
    if "own" in a:  # a filtered buffer: each pixel's own samples (not the border's, a neighbour's)
        found = found & (a["own"] > 0)
    pix = a["pixel"][found].astype(np.intp)  # bincount would convert uint32 on every call
    size = buf.width * buf.height
    count = np.bincount(pix, minlength=size).astype(np.float64)
    v = values[:, found]
    s1 = np.stack([np.bincount(pix, weights=c, minlength=size) for c in v])
    s2 = np.stack([np.bincount(pix, weights=c * c, minlength=size) for c in v])
    n = np.maximum(count, 1.0)
    mean = s1 / n
    with np.errstate(divide="ignore", invalid="ignore"):
        var = np.maximum(s2 / n - mean * mean, 0.0) / (count - 1.0)
    var[:, count < 2] = np.nan
    return count, mean, var


def raster(scene, p) -> np.ndarray:
    """Each vertex's position on the film in pixels of the crop window: where its camera ray left
    the sensor, found by projecting the vertex (`Sensor.sample_direction`'s uv).

    Args:
        scene: the scene (its first sensor). p: the vertices, 3 x N (numpy or a Dr.Jit 3-vector).

    Returns:
        N x 2 float64.
    """
    uv = _raster(scene, p if not isinstance(p, np.ndarray) else
                 mi.Point3f(*(mi.Float(aligned(p[i])) for i in range(3))))
    return np.stack([np.asarray(uv.x, dtype=np.float64), np.asarray(uv.y, dtype=np.float64)], -1)


def _raster(scene, p) -> mi.Point2f:
    """`raster` on the device: the film positions, mi.Point2f (crop window pixels)."""
    sensor = scene.sensors()[0]
    it = dr.zeros(mi.Interaction3f, dr.width(p))
    it.p = mi.Point3f(p)
    ds, _ = sensor.sample_direction(it, mi.Point2f(0.5, 0.5))
    # uv is in pixels of the crop window already (tests/denoise/test_expectation.py measures it on
    # a crop)
    return mi.Point2f(ds.uv)


def at_samples(buf: Buffer, d: np.ndarray, scene, g: guides.Guides, own: tuple) -> np.ndarray:
    """D at each camera sample's own film position, remodulated by its albedo, its emission added.

    Bilinear between the four nearest pixel centres that show the sample's own surface
    (`Field.lookup`), renormalised; the own pixel's D where none does or the projection fails.

    Args:
        buf: the buffer of means. d: D, H x W x 3 (the reflected part). scene: the scene.
        g: the pixel-footprint guides. own: (albedo, emission) at each sample's vertex, N x 3 each
            (`own_surface`) or mi.Color3f each (`own_on_device`).

    Returns:
        3 x N float32 (`at_samples_on_device`'s values on the host).
    """
    return np.asarray(at_samples_on_device(buf, d, scene, g, own), dtype=np.float32)


def _color(x) -> mi.Color3f:
    """A mi.Color3f of an N x 3 host array (float32 on the device), or of a Dr.Jit one."""
    if not isinstance(x, np.ndarray):
        return mi.Color3f(x)
    return mi.Color3f(*(mi.Float(aligned(x[:, i])) for i in range(3)))


def at_samples_on_device(buf: Buffer, d: np.ndarray, scene, g: guides.Guides,
                         own: tuple) -> mi.Color3f:
    """`at_samples` on the device: one kernel, the buffer's arrays read where they lie.

    Args:
        buf, d, scene, g, own: as `at_samples`'s.

    Returns:
        mi.Color3f, evaluated: D at each camera sample (the buffer's DENOISED array).
    """
    a = buf.arrays
    w = buf.width
    pixel = a["pixel"]
    found_host = a["slot"] >= 0
    if not found_host.any():  # the fallback everywhere: the sample's own pixel's D
        pix = pixel.astype(np.int64)
        flat = np.ascontiguousarray(d[pix // w, pix % w].T.astype(np.float32))
        return mi.Color3f(*(mi.Float(flat[i]) for i in range(3)))
    own_albedo, emission = (_color(x) for x in own)
    found = mi.Bool(found_host)
    pix = mi.UInt32(pixel)
    p = field(buf, "p")
    if "pos" in a:  # where the render loop put the sample (filtered buffers), in crop pixels
        off = buf.header["crop_offset"]
        # float32 pos less an integer offset of the same film: exact, as the float64 of before
        uv = field(buf, "pos") - mi.ScalarVector2f(float(off[0]), float(off[1]))
    else:
        uv = _raster(scene, p)
    good = found & dr.isfinite(uv.x) & dr.isfinite(uv.y)
    good &= (dr.floor(uv.x) == mi.Float(pix % w)) & (dr.floor(uv.y) == mi.Float(pix // w))
    diag = float(np.linalg.norm(np.asarray(scene.bbox().extents())))
    fx = dr.select(good, uv.x, 0.5)
    fy = dr.select(good, uv.y, 0.5)
    # samples without a vertex keep their pixel's D as it is: no albedo (no remodulation),
    # no emission
    albedo = dr.select(found, own_albedo, dr.nan)
    emitted = dr.select(found, emission, 0.0)
    probe = Probe(mi.Point2f(fx, fy), mi.Point3f(p), field(buf, "n"), pix, mi.Bool(True), good)
    out = Field(d, g, diag).at(probe, albedo, emitted)
    dr.eval(out)  # one kernel for the three channels
    return out


class Field:
    """D and its guides as Dr.Jit arrays, for lookups inside a kernel (`lookup`, `at`): `at_samples`
    for the camera samples, `coverage.CoverageIntegrator` for its points.

    Args:
        d: D, H x W x 3. g: the pixel-footprint guides (`guides.Guides`).
        diag: the scene's bounding-box diagonal (the scale of the same-surface test's tolerance).
    """

    def __init__(self, d: np.ndarray, g: guides.Guides, diag: float):
        #: whether D is the reflected part alone (`EMISSION_APART`): a lookup adds the vertex's own
        #: emission back
        self.emission_apart = EMISSION_APART
        #: D's relative uncertainty per pixel (Dr.Jit Float, H x W) where the style is averaged over
        #: it, else None
        self.spread = None

        def image(a):
            return mi.Float(aligned(np.ravel(a)))
        self.h, self.w = d.shape[:2]
        self.diag = float(diag)
        self.D, self.A, self.NRM, self.POS = (
            image(d),
            image(g.albedo),
            image(g.surface_normal),
            image(g.position),
        )

    @staticmethod
    def _get(img, idx, mask):
        return mi.Vector3f(dr.gather(mi.Vector3f, img, idx, mask))

    def lookup(self, probe: Probe, albedo=None):
        """Sums over the four pixel centres around the probe's film position of w D, w albedo and
        w; w: the bilinear weight where the pixel shows the vertex's own surface, else 0.

        Args:
            probe: the vertex (its film position, position, normal, pixel and lanes).
            albedo: the vertex's own albedo (mi.Color3f; None or not finite: its pixel's guide
                albedo).

        Returns:
            (sum of w D, sum of w albedo: mi.Vector3f each; sum of w: mi.Float). Own surface: the
            normal within ~18 degrees, the hit ~6 degrees of the tangent plane, albedo within 0.05.
        """
        ps, ns, pix, valid = probe.p, probe.n, probe.pixel, probe.valid
        near = valid if probe.near is None else probe.near
        w, h, get = self.w, self.h, self._get
        fx, fy = probe.film.x - 0.5, probe.film.y - 0.5
        a_s = get(self.A, pix, valid)
        if albedo is not None and OWN_ALBEDO:
            albedo = mi.Vector3f(albedo)
            a_s = dr.select(dr.all(dr.isfinite(albedo)), albedo, a_s)
        x0, y0 = mi.Int32(dr.floor(fx)), mi.Int32(dr.floor(fy))
        acc, acc_a, wsum = mi.Vector3f(0.0), mi.Vector3f(0.0), mi.Float(0.0)
        for dy in (0, 1):
            for dx in (0, 1):
                qx, qy = dr.clip(x0 + dx, 0, w - 1), dr.clip(y0 + dy, 0, h - 1)
                q = mi.UInt32(qy * w + qx)
                wt = dr.clip(1 - dr.abs(fx - mi.Float(x0 + dx)), 0, 1) * dr.clip(
                    1 - dr.abs(fy - mi.Float(y0 + dy)), 0, 1
                )
                gap = get(self.POS, q, valid) - ps
                aq = get(self.A, q, valid)
                same = dr.dot(get(self.NRM, q, valid), ns) > 0.95
                same &= dr.abs(dr.dot(gap, ns)) <= 0.1 * dr.norm(gap) + 1e-5 * self.diag
                same &= dr.max(dr.abs(aq - a_s)) <= 0.05
                wt = dr.select(valid & near & same, wt, 0.0)
                acc += wt * get(self.D, q, valid)
                acc_a += wt * aq
                wsum += wt
        return acc, acc_a, wsum

    def at(self, probe: Probe, own_albedo, emission) -> mi.Color3f:
        """D for one vertex inside a kernel: interpolated (`lookup`), remodulated, emission added.

        Remodulated (REMODULATE): D x the vertex's own albedo / the albedo D was formed under (the
        guide albedo with the same weights), per channel, where both are positive. Design:
        docs/design/expectation_denoising.md.

        Args:
            probe: the vertex, as `lookup`'s. own_albedo: its albedo (mi.Color3f; NaN: left as it
                is). emission: its own emitted radiance (mi.Color3f).

        Returns:
            mi.Color3f: D (the own pixel's where no neighbour qualifies), remodulated, + emission.
        """
        pix, valid = probe.pixel, probe.valid
        acc, acc_a, wsum = self.lookup(probe, own_albedo)
        some = wsum > 1e-6
        inv = dr.rcp(dr.maximum(wsum, 1e-12))
        out = dr.select(some, acc * inv, self._get(self.D, pix, valid))
        if REMODULATE:
            mixed = dr.select(some, acc_a * inv, self._get(self.A, pix, valid))
            ok = (mixed > 1e-4) & (own_albedo > 0)
            out = out * dr.select(ok, own_albedo / dr.select(ok, mixed, 1.0), 1.0)
        return mi.Color3f(out + emission)


#: the lookup's same-surface test compares a neighbour's albedo with the vertex's own
#: (`Field.lookup`)
OWN_ALBEDO = True
#: rescale D at each camera sample by its own albedo over the pixel's (`Field.at`)
REMODULATE = True
#: denoise the reflected part of E[L] and add each sample's own emission back (`own_surface`)
EMISSION_APART = True


def own_surface(scene, a) -> tuple[np.ndarray, np.ndarray]:
    """(albedo, emission) at each camera sample's own vertex, found again by a ray from just in
    front of the vertex (along wo) back onto it: `own_on_device`'s, on the host.

    Args:
        scene: the scene. a: the buffer's arrays (`p`, `wo`: 3 x N; a `buffer.Arrays` is read where
            its arrays lie, a dict of numpy arrays on the host).

    Returns:
        (albedo, emission), N x 3 float64 each (see `own_on_device`).
    """
    if hasattr(a, "parts"):
        p, wo = field(a, "p"), field(a, "wo")
    else:
        p, wo = (mi.Vector3f(*(mi.Float(aligned(a[k][i]))
                               for i in range(3))) for k in ("p", "wo"))
    albedo, emission = own_on_device(scene, p, wo)
    return np.asarray(albedo, dtype=np.float64).T, np.asarray(emission, dtype=np.float64).T


def own_on_device(scene, p, wo) -> tuple[mi.Color3f, mi.Color3f]:
    """(albedo, emission) at each vertex, found again by a ray from just in front of the vertex
    (along wo) back onto it; one kernel, evaluated.

    Args:
        scene: the scene. p, wo: the vertices and their directions towards the viewer (Dr.Jit
            3-vectors, float32).

    Returns:
        (albedo, emission), mi.Color3f each. albedo: as `guides.first_hit` forms it (through
        mirrors and glass); NaN where the vertex is not found again (`Field.at` then leaves the
        sample as it is). emission: the radiance the vertex emits towards wo (0 elsewhere, where
        not found and where NaN); `attach` denoises the reflected part alone and adds it back per
        sample.
    """
    diag = float(np.linalg.norm(np.asarray(scene.bbox().extents())))
    eps = 1e-4 * max(diag, 1e-6)
    # the ray's origin p + wo eps in float64, rounded to float32 once, unfused: as numpy formed it
    # before the arrays stayed on the device (the same origins, bit for bit)
    with dr.scoped_set_flag(dr.JitFlag.FastMath, False):
        o = mi.Point3f(*(mi.Float(mi.Float64(p[i]) + mi.Float64(wo[i]) * eps) for i in range(3)))
        dr.eval(o)
    ray = mi.Ray3f(o, -mi.Vector3f(wo))
    ray.maxt = mi.Float(3.0 * eps)
    si = scene.ray_intersect(ray)
    dr.eval(si)  # measured: the chain after an evaluated hit costs half of one kernel doing both
    found = si.is_valid()
    alb, _ = guides.through_delta(scene, si, found)
    le = mi.Color3f(si.emitter(scene, found).eval(si, found))
    albedo = dr.select(found, alb, dr.nan)  # not found again: no correction for this sample
    emission = dr.select(found & ~dr.isnan(le), le, 0.0)
    # one kernel: reading the channels one by one would trace the chain three times
    dr.eval(albedo, emission)
    return albedo, emission


#: OIDN's output is trusted down to this fraction of the image's mean brightness (see
#: `below_resolution`)
RESOLUTION = 1e-3


def below_resolution(d: np.ndarray, m: np.ndarray) -> np.ndarray:
    """D with the pixels darker than RESOLUTION x M's mean brightness set to 0, negatives clipped.

    Below the denoiser's resolution the value carries no information, only a little of the
    neighbours' light that OIDN leaks. Design: docs/design/expectation_denoising.md.

    Args:
        d: D, H x W x 3. m: M, H x W x 3.

    Returns:
        The new D, H x W x 3.
    """
    lum = d.mean(-1)
    scale = float(np.mean(m.mean(-1)))
    out = d.copy()
    out[lum < RESOLUTION * scale] = 0.0
    return np.maximum(out, 0.0)


@dataclass(frozen=True)
class Carried:
    """What the calls of `attach` for one render share.

    Args:
        cache: a dict kept between calls on one growing buffer (`ExpectationJob`'s), in which the
            guides of each spp and the own albedo and emission of each pass are made once (the
            same values as made anew); None: nothing kept.
        pilot: the render's scene-defaults pilot (`scene.defaults.ScenePilot`) for the points'
            buffer, or None: traced anew.
        history: the frames' `denoise.temporal.History` (M blended with it, D held by it; the
            caller commits), or None.
    """
    cache: dict | None = None
    pilot: Any = None
    history: Any = None


def attach(
    buf: Buffer,
    shot: Shot,
    quality: str = "high",
    k: int = 0,
    uncertainty: float = 0.0,
    carried: Carried = Carried(),
):
    """Denoise the buffer's expectation: M formed (blended with the frames' history where one is
    given), denoised into D, g's points placed.

    Args:
        buf: the recorded buffer of means. shot: its scene, the render's integrator (read for
            k > 0 only), camera samples per pixel (the guides') and seed.
        quality: OIDN's. uncertainty: `spread`'s (> 0).
        k: 0: D kept at each camera sample in the buffer; > 0: g at k points (`coverage.points`).
        carried: the render's cache, pilot and frames' history (`Carried`).

    Returns:
        (D per pixel H x W x 3, None) for k = 0; (D, the points' buffer) for k > 0. The arrays
        the kernels write stay on the device until read (`lookdev.buffer.Arrays`).

    Raises:
        UsageError: a buffer that does not store means.
    """
    scene, integrator, spp, seed = shot.scene, shot.integrator, shot.spp, shot.seed
    cache, history = carried.cache, carried.history
    if buf.stores != "mean":
        raise UsageError(
            "--denoise expectation needs a buffer of children means (direct or affine estimator)"
        )
    # a still shot's frames share their guides and points (`temporal.History.shared`): only the
    # estimate changes from one frame to the next
    view_seed = seed if history is None else history.shared("seed", seed)
    g = _guides(scene, spp, view_seed, cache)  # M's footprint
    own = _own_device(scene, buf, cache)
    # the reflected part: each sample's own emission goes back in at_samples
    refl = _reflected(buf, own[1])
    m = _expectation(buf, refl) if history is None else _blended(buf, refl, history)
    d = oidn.denoise_oidn(m, g.albedo, g.normal, quality, guides.to_sensor(scene))
    d = below_resolution(d, m)
    if history is not None:
        d = history.hold(d)
    header = {"method": "expectation", "quality": quality,
              "guides": "albedo and shading normal through specular chains (guides.first_hit)",
              "at_samples": "guided bilinear interpolation of D at each sample's film position"}
    if k:
        lookup = Field(d, g, float(np.linalg.norm(np.asarray(scene.bbox().extents()))))
        rel = _spread(buf, refl, uncertainty) if uncertainty > 0 else None
        if rel is not None:
            lookup.spread = mi.Float(aligned(rel.ravel()))
        cover = coverage_module.points(scene, integrator, lookup, k, view_seed,
                                       pilot=carried.pilot)
        if rel is not None:  # per point, its pixel's: restyles average g over it too
            cover.arrays[SPREAD] = dr.gather(mi.Float, lookup.spread,
                                             mi.UInt32(aligned(cover.arrays["pixel"], np.uint32)))
        cover.header["denoise"] = {**header, "coverage": k, "uncertainty": float(uncertainty)}
        cover.header["scene"] = buf.header.get("scene", "")  # the points keep the render's name
        if cover.stylize == "first_object_hit":
            denoise_before(cover, g, quality, scene)
        elif cover.filtered:  # the render loop splatted each point at its sample_pos, not its own
            cover.image = image_of(cover)
        return d, cover
    buf.arrays[DENOISED] = at_samples_on_device(buf, d, scene, g, own)
    buf.header["denoise"] = header
    buf.device.clear()  # the Dr.Jit copy must pick up the denoised means
    return d, None


def _blended(buf: Buffer, refl: np.ndarray, history) -> np.ndarray:
    """M blended with the frames' history (`temporal.History.blend`): each pixel's mean of its
    samples' reflected parts (3 x N, `_reflected`) with its variance and count, the frames'
    weights and test."""
    count, mean, var = _sample_moments(buf, refl)
    hw3 = (buf.height, buf.width, 3)
    return history.blend(mean.T.reshape(hw3), var.T.reshape(hw3),
                         count.reshape(buf.height, buf.width))


def denoise_before(cover: Buffer, g: guides.Guides, quality: str, scene) -> None:
    """`first_object_hit`'s light gathered before the styled vertex, denoised: per pixel the mean
    of the points' L_before (surfaces without a style, path traced by each point's own walk: as
    noisy as a render of k samples) goes through OIDN with the guides, as the image denoiser
    treats a physically based image, and every point takes its pixel's value, so that the buffer
    restyles to the denoised image (`cover.image`: the pass's, the pixel's mean of L_before
    exchanged for its denoised value).

    Args:
        cover: the coverage points' buffer (changed in place). g: the pixel-footprint guides.
        quality: OIDN's. scene: the scene (its sensor, for the normals' frame).
    """
    before = np.asarray(cover.arrays["L_before"], dtype=np.float64)
    every = np.ones(cover.camera_samples, bool)
    m = _sample_moments(cover, before, every)[1].T.reshape(cover.height, cover.width, 3)
    d = oidn.denoise_oidn(m.astype(np.float32), g.albedo, g.normal, quality,
                          guides.to_sensor(scene))
    d = np.maximum(d, 0.0)
    pixel = np.asarray(cover.arrays["pixel"]).astype(np.intp)
    cover.arrays["L_before"] = np.ascontiguousarray(d.reshape(-1, 3)[pixel].T, dtype=np.float32)
    cover.device.clear()  # the Dr.Jit copy must pick up the new values
    if cover.filtered:  # splatted with the film's filter: made as a restyle makes it
        cover.image = image_of(cover)
        return
    # the kernel's own image, so that a restyle equals it up to rounding as it did before
    image = np.array(cover.image, dtype=np.float32)
    image[..., :3] += (d - m).astype(np.float32)
    cover.image = image


def _guides(scene, spp: int, seed: int, cache: dict | None) -> guides.Guides:
    """M's guides (`guides.first_hit`, the pixel footprint), kept in `cache` per spp."""
    key = ("guides", int(spp), int(seed))
    if cache is not None and key in cache:
        return cache[key]
    g = guides.first_hit(scene, spp, pass_seed(seed, 0), footprint="pixel")
    if cache is not None:
        for old in [c for c in cache if isinstance(c, tuple) and c[0] == "guides"]:
            del cache[old]
        cache[key] = g
    return g


def _own_device(scene, buf: Buffer, cache: dict | None) -> tuple[mi.Color3f, mi.Color3f]:
    """(albedo, emission) at every camera sample's vertex (`own_on_device`), the emission 0 unless
    EMISSION_APART; with a cache, those of the passes done before are kept (keyed by the passes'
    own `p` and `wo` arrays) and only the new passes' traced, in one kernel."""
    p_parts, wo_parts = buf.arrays.parts("p"), buf.arrays.parts("wo")
    pairs = list(zip(p_parts, wo_parts))
    done = cache.get("own", []) if cache is not None else []
    kept, at = [], 0
    for parts, albedo, emission in done:  # the kept entries that still match the buffer's passes
        here = pairs[at:at + len(parts)]
        if len(here) != len(parts) or any(a is not b or c is not e
                                          for (a, c), (b, e) in zip(here, parts)):
            break
        kept.append((parts, albedo, emission))
        at += len(parts)
    if at < len(pairs):
        new = pairs[at:]
        p, wo = (joined([x[i] for x in new], "Vector3f") for i in (0, 1))
        albedo, emission = own_on_device(scene, p, wo)
        if not EMISSION_APART:
            emission = dr.zeros(mi.Color3f, dr.width(albedo))
        kept.append((new, albedo, emission))
    if cache is not None:
        cache["own"] = kept
    albedo = joined([e[1] for e in kept], "Color3f")
    emission = joined([e[2] for e in kept], "Color3f")
    return albedo, emission


#: `uncertainty` by default: D's residual error as a fraction of the noisy M's standard error. 0:
#: g of D itself. 0.3 had the least squared error on the Cornell box (BENCHMARKS.md denoise), but
#: on an interior its five-node average drew stepped rings around every band edge, where 0 keeps
#: the bands flat and sharp (docs/design/expectation_denoising.md, "The uncertainty's default")
UNCERTAINTY = 0.0


def check_uncertainty(value) -> float:
    """`uncertainty` as a float.

    Args:
        value: a number from 0 (g of D itself) to 10: D's residual error as a fraction of the noisy
            estimate's standard error.

    Returns:
        The float.

    Raises:
        UsageError: anything else, bools included (one line naming the value).
    """
    try:
        u = float(value)
    except (TypeError, ValueError):
        u = float("nan")
    if isinstance(value, bool) or not np.isfinite(u) or u < 0 or u > 10:
        raise UsageError(
            f"bad value {value!r} for denoise uncertainty: expected a number from 0 (g of D "
            "itself) to 10, the residual error of D as a fraction of the noisy estimate's standard "
            "error"
        )
    return u


def spread(buf: Buffer, emission: np.ndarray, uncertainty: float) -> np.ndarray:
    """D's relative uncertainty per pixel: `uncertainty` x the relative standard error of M.

    That error comes from the spread of M's camera samples' children means (brightness,
    emission taken off), its square averaged over the pixel's 3 x 3 neighbourhood (edges repeated;
    under 2 samples with a stylized vertex count 0), capped at 1. Design: expectation_denoising.md.

    Args:
        buf: the buffer of means. emission: each sample's own emission, N x 3 or a mi.Color3f.
        uncertainty: the factor (`check_uncertainty`).

    Returns:
        H x W float64 in [0, 1]; it goes to 0 as the samples grow.
    """
    return _spread(buf, _reflected(buf, emission), uncertainty)


def _spread(buf: Buffer, refl: np.ndarray, uncertainty: float) -> np.ndarray:
    """`spread` of the samples' reflected parts (3 x N, `_reflected`)."""
    _, mean, var = _sample_moments(buf, refl.mean(0, keepdims=True))
    mean, var_of_mean = mean[0], np.nan_to_num(var[0])  # below 2 samples: 0
    floor = 1e-3 * max(float(np.abs(mean).mean()), 1e-12)
    rel2 = (var_of_mean / np.maximum(np.abs(mean), floor) ** 2).reshape(buf.height, buf.width)
    return np.minimum(uncertainty * np.sqrt(box3(rel2)), 1.0)


def _own(scene, buf: Buffer) -> tuple[np.ndarray, np.ndarray]:
    own_albedo, emission = own_surface(scene, buf.arrays)
    if not EMISSION_APART:
        emission = np.zeros_like(emission)
    return own_albedo, emission


def image_of(buf: Buffer) -> np.ndarray:
    """The buffer's image with its recorded styles (denoised where the buffer holds D).

    Args:
        buf: the buffer.

    Returns:
        H x W x 3 float32.
    """
    slots = prepare_slots(buf, slots_for(buf))
    return np.asarray(accumulate(buf, sample_values(buf, slots)), dtype=np.float32).reshape(
        buf.height, buf.width, 3
    )


def noisy_variance(buf: Buffer) -> np.ndarray:
    """The variance of each pixel's *undenoised* estimate from its camera samples' values.

    That is (mean of squares - squared mean) / (spp - 1), as `pipeline.passes.Progress.aovs` defines
    `variance`; NaN below 2 samples. D, where the buffer holds it, is left out (of a view that
    shares the buffer's arrays: the buffer itself is not changed).

    Args:
        buf: the buffer.

    Returns:
        H x W x 3 float32.
    """
    noisy = Buffer(buf.header, buf.arrays.copy())
    if DENOISED in noisy.arrays:
        del noisy.arrays[DENOISED]
    slots = prepare_slots(noisy, slots_for(noisy))
    vals = np.asarray(sample_values(noisy, slots), dtype=np.float64)
    # every sample, vertex or not
    var = _sample_moments(noisy, vals, np.ones(noisy.camera_samples, bool))[2]
    return var.T.reshape(buf.height, buf.width, 3).astype(np.float32)


def render_denoised_expectation(
    shot: Shot,
    denoising: Denoising = Denoising("expectation"),
    split: PassSplit = PassSplit(),
    max_camera_samples: int = MAX_CAMERA_SAMPLES,
    label: str = "",
    callback: Callable[[Progress], None] | None = None,
) -> tuple[np.ndarray, Buffer]:
    """The denoised-expectation render: `ExpectationJob`'s passes, then its `finish`.

    Args:
        shot, denoising, split, max_camera_samples, label: as `ExpectationJob`'s.
        callback: called with each `Progress`.

    Returns:
        (the image, H x W x 3 float32; its buffer, whose `image` is the noisy render). With coverage
        k > 0 the buffer is the coverage points' (`buf.source`: the camera samples').

    Raises:
        UsageError: a refusal of `ExpectationJob` or of its `finish`.
    """
    job = ExpectationJob(shot, denoising, max_camera_samples, label, split)
    for prog, _ in job.passes():
        if callback is not None:
            callback(prog)
    return job.finish()


class ExpectationJob:
    """A denoised-expectation render in two steps, for callers that show and cancel passes:
    `passes()` records the noisy buffer (`buffer`), `finish()` denoises it and applies g.

    Args:
        shot: what to render (its error AOVs come from the buffer, `aovs`), its spp and seed.
        denoising: OIDN's quality, the points per pixel where g meets D (its coverage,
            `coverage.resolve_k`) and `spread`'s uncertainty (None: UNCERTAINTY); its method and
            footprint are not read.
        max_camera_samples: the buffer's cap. label: the scene's label.
        split: the pass split (`pipeline.passes.PassSplit`).
        pilot: the scene-defaults pilot the job was resolved with (`pipeline.resolve`), or None:
            one of the job's own, traced once for the passes and the coverage points.

    Raises:
        UsageError: no pyoidn, a bad quality, coverage or uncertainty, or an unsupported render
            (`pipeline.denoising.check_expectation`), refused when the job is made, before
            anything renders.
    """

    def __init__(
        self,
        shot: Shot,
        denoising: Denoising = Denoising("expectation"),
        max_camera_samples: int = MAX_CAMERA_SAMPLES,
        label: str = "",
        split: PassSplit = PassSplit(),
        pilot: ScenePilot | None = None,
    ):
        quality = denoising.quality
        oidn.require()
        oidn.check_quality(quality)
        integrator = shot.integrator
        check_expectation(integrator)
        w, h = (int(v) for v in shot.scene.sensors()[0].film().crop_size())
        self.k = coverage_module.resolve_k(denoising.coverage, w, h, max_camera_samples)
        uncertainty = UNCERTAINTY if denoising.uncertainty is None else denoising.uncertainty
        self.uncertainty = check_uncertainty(uncertainty)
        # the buffer records without them; `aovs` below derives them from it
        if integrator.settings.aovs:
            integrator = StylizedIntegrator.from_values({**integrator.values, "aovs": False})
        #: what the job renders (its integrator without error AOVs), its spp and seed
        self.shot = replace(shot, integrator=integrator)
        self.quality, self.max_camera_samples, self.label, self.split = (
            quality,
            max_camera_samples,
            label,
            split,
        )
        #: the noisy buffer of the passes recorded so far (None before the first)
        self.buffer: Buffer | None = None
        #: what `attach` keeps between a preview and the next preview or `finish` (`attach`'s)
        self._cache: dict = {}
        #: the frames' temporal history (`denoise.temporal`), committed by `finish`, or None
        self.history = denoising.history
        #: the scene-defaults pilot of the passes and the points (traced once, where first used)
        self.pilot = (pilot if pilot is not None and pilot.serves(shot.scene, integrator.settings)
                      else ScenePilot(shot.scene, integrator.settings))

    def passes(self) -> Iterator[tuple[Progress, Buffer]]:
        """Record the noisy buffer pass by pass (`lookdev.record.record`).

        Returns:
            An iterator of (the pass's `Progress`, the buffer so far: `buffer`, its `image` the
            noisy render so far).

        Raises:
            StyletraceError: what `record` refuses (one line).
        """
        self._cache = {}
        for prog, buf in record(self.shot, self.split, self.label or scene_label(None),
                                self.max_camera_samples, self.pilot):
            buf.image = prog.image
            self.buffer = buf
            yield prog, buf

    def finish(self) -> tuple[np.ndarray, Buffer]:
        """Denoise the recorded buffer and apply g: the render's result.

        Returns:
            (the denoised image, H x W x 3 float32; the buffer that restyles to it: with coverage
            points theirs, `source` the camera samples' buffer; with k = 0 the recorded buffer,
            D at its samples).

        Raises:
            UsageError: not every pixel has a camera sample yet (a render cancelled in its first
                round of tiles; one line).
        """
        out = self._finish(self.buffer, self.k, self.quality)
        if self.history is not None:
            self.history.commit()
        return out

    def preview(self, k: int | str = 1, quality: str = "fast") -> tuple[np.ndarray, Buffer]:
        """A quick denoised image of the passes so far, for a viewport; `finish` is not changed.

        Args:
            k: where g meets D: 0 at the camera samples (D looked up at each), else k coverage
                points per pixel (a square: 1, one per pixel, is the cheapest; "auto" as a render),
                within the buffer's cap (`coverage.resolve_k`).
            quality: OIDN's: "fast", "balanced" or "high" (`finish`'s is the job's).

        Returns:
            (the image, H x W x 3 float32; the buffer that restyles to it, as `finish`'s, but for
            k = 0 a copy of the recorded buffer sharing its arrays, with D at its samples: the
            recorded buffer, its `source`, stays noisy for the passes to come). The guides and each
            pass's own albedo and emission are kept for the next preview and for `finish`.

        Raises:
            UsageError: no pass finished yet, a bad k or quality (one line).
        """
        oidn.check_quality(quality)
        w, h = (int(v) for v in self.shot.scene.sensors()[0].film().crop_size())
        k = coverage_module.resolve_k(k, w, h, self.max_camera_samples)
        buf = self.buffer
        if k == 0 and buf is not None:
            view = Buffer(copy.deepcopy(buf.header), buf.arrays.copy(), image=buf.image)
            image, out = self._finish(view, 0, quality)
            out.source = buf
            return image, out
        return self._finish(buf, k, quality)

    def _finish(self, buf: Buffer | None, k: int, quality: str) -> tuple[np.ndarray, Buffer]:
        if buf is None or buf.spp < 1:
            raise UsageError("nothing to denoise: no pass of the render finished")
        # the guides of as many camera samples as the buffer holds (a preview's: fewer)
        shot = replace(self.shot, spp=buf.spp)
        _, cover = attach(buf, shot, quality, k, self.uncertainty,
                          Carried(self._cache, self.pilot, self.history))
        if cover is None:
            return image_of(buf), buf
        image = np.asarray(cover.image, dtype=np.float32)[..., :3]
        cover.image, cover.source = buf.image, buf
        return image, cover


def aovs(buf: Buffer, image: np.ndarray) -> dict[str, np.ndarray]:
    """Honest error AOVs of a denoised-expectation render (docs/denoise.md).

    Args:
        buf: the render's buffer (for coverage points their `source`, the camera samples, is read).
        image: the denoised image, H x W x 3.

    Returns:
        {"noisy_variance": the pixel's variance *before* denoising (not the denoised pixel's error,
        which no per-pixel statistic here measures), "children": n per camera sample (H x W),
        "denoise_change": denoised - noisy image}.
    """
    src = getattr(buf, "source", None) or buf  # coverage points: the camera samples with children
    n = max(int(s["inner"]) for s in src.header["slots"])
    return {
        "noisy_variance": noisy_variance(src),
        "children": np.full((src.height, src.width), float(n), dtype=np.float32),
        "denoise_change": (
            np.asarray(image, np.float32) - np.asarray(src.image, np.float32)[..., :3]
        ),
    }


__all__ = [
    "render_denoised_expectation",
    "ExpectationJob",
    "attach",
    "Field",
    "expectation",
    "image_of",
    "noisy_variance",
    "aovs",
    "DENOISED",
]
