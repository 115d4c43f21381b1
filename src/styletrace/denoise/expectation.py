"""Denoising the expectation before the style: `--denoise expectation`.

    image, buf = render_denoised_expectation(scene, integrator, spp=16, seed=0, quality="high")

Per camera sample the renderer records the stylized vertex, the radiance before it and the mean of
its children (`lookdev.record`). Per pixel M averages those means, less each sample's own emission
(`expectation`); OIDN denoises M with the guides into D (`attach`), and every camera sample takes
its own slot's g of D interpolated at its own film position (`at_samples`), or with coverage g is
evaluated at k stratified points per pixel (`coverage`). D at the samples is kept in the buffer
(`DENOISED`), so a restyle styles D too. Supported and refused: `check_expectation`.
Design: docs/design/expectation_denoising.md.
"""
from __future__ import annotations

from typing import Callable, Iterator

import numpy as np

from styletrace.config import settings as S
from styletrace.denoise import coverage as coverage_module
from styletrace.denoise import guides, oidn
from styletrace.errors import UsageError
from styletrace.gate import dr, mi
from styletrace.kernel.integrator import StylizedIntegrator
from styletrace.lookdev.buffer import MAX_SAMPLES, SPREAD, Buffer
from styletrace.lookdev.record import record, scene_label
from styletrace.lookdev.restyle import (
    RESTYLABLE_ESTIMATORS,
    accumulate,
    prepare_slots,
    sample_values,
    slots_for,
)
from styletrace.pipeline.passes import LANES_PER_PASS, Progress, pass_seed

#: the buffer array holding the denoised expectation at each camera sample (3 x samples, as `mean`)
DENOISED = "denoised_mean"


def check_expectation(integrator) -> None:
    """Refuse what the expectation denoiser does not support.

    Supported: `first_hit` with the integrator's style and per-object (`styled`) styles, the
    `direct` and `affine` estimators, fixed counts n (films other than rgb: the buffer's refusal).

    Args:
        integrator: the render's `stylized` integrator.

    Raises:
        UsageError: first_object_hit, first_n_hits or stylize_depth > 1, lines, reuse, the expansion
            pass, another estimator, adaptive counts, a per-sample style (one line each).
    """
    s = integrator.settings
    why = None
    if s.stylize == "first_object_hit":
        why = (
            "stylize=first_object_hit: its stylized vertex may lie behind a mirror or glass, where "
            "the pixel's guides describe another surface; use first_hit or --denoise image"
        )
    elif s.stylize == "first_n_hits" or s.stylize_depth != 1:
        why = (
            "stylize=first_n_hits: nested levels have no per-pixel expectation to denoise (the "
            "inner levels' vertices are not the pixel's); use first_hit or --denoise image"
        )
    elif s.lines is not None:
        why = "feature lines: lines replace radiance inside the estimate; use --denoise image"
    elif s.reuse != "off":
        why = f"reuse={s.reuse}: denoising and reuse both filter the expectation; use one"
    elif s.expansion_pass:
        why = ("expansion_pass: it serves the series estimators, which denoising replaces by "
               "direct application")
    elif s.slot.estimator not in RESTYLABLE_ESTIMATORS:
        why = (
            f"estimator '{s.slot.estimator}': the denoised expectation is styled by direct "
            "application; use direct or affine"
        )
    elif S.adaptive(s.inner):
        why = "adaptive counts n0:n_max: give a fixed count (the denoiser does the averaging)"
    elif s.style.per_sample:
        why = (f"style '{s.style.name}': it applies g to every child, there is no expectation to "
               "denoise")
    if why is not None:
        raise UsageError(f"--denoise expectation cannot render {why}")


def expectation(buf: Buffer, emission: np.ndarray | None = None) -> np.ndarray:
    """M: per pixel, the mean of its camera samples' children means where a stylized vertex was
    found (0 where none was).

    Args:
        buf: the buffer of means. emission: each sample's own emitted radiance (N x 3,
            `own_surface`), taken off first (M is then the reflected part alone), or None.

    Returns:
        M, H x W x 3 float32.
    """
    return (
        _sample_moments(buf, reflected(buf, emission))[1]
        .reshape(buf.height, buf.width, 3)
        .astype(np.float32)
    )


def reflected(buf: Buffer, emission: np.ndarray | None) -> np.ndarray:
    """Each camera sample's children mean, less its own emission where given.

    Args:
        buf: the buffer of means. emission: N x 3, or None.

    Returns:
        N x 3 float64.
    """
    mean = buf.arrays["mean"].astype(np.float64).T
    return mean if emission is None else mean - emission


def _sample_moments(buf: Buffer, values: np.ndarray, found: np.ndarray | None = None):
    """Per pixel, over its samples with a stylized vertex (or those of `found`) of `values` (N x C):
    (count, mean, variance of the mean = (mean of squares - squared mean) / (count - 1)); mean 0
    where a pixel has no such sample, variance NaN below 2. Float64, flat over the pixels (H*W, and
    H*W x C)."""
    a = buf.arrays
    found = a["slot"] >= 0 if found is None else found
    if "own" in a:  # a filtered buffer: each pixel's own samples (not the border's, a neighbour's)
        found = found & (a["own"] > 0)
    pix = a["pixel"].astype(np.int64)[found]
    size = buf.width * buf.height
    count = np.bincount(pix, minlength=size).astype(np.float64)
    v = values[found]
    s1 = np.stack(
        [np.bincount(pix, weights=v[:, c], minlength=size) for c in range(v.shape[1])], -1
    )
    s2 = np.stack(
        [np.bincount(pix, weights=v[:, c] * v[:, c], minlength=size) for c in range(v.shape[1])], -1
    )
    n = np.maximum(count, 1.0)[:, None]
    mean = s1 / n
    with np.errstate(divide="ignore", invalid="ignore"):
        var = np.maximum(s2 / n - mean * mean, 0.0) / (count[:, None] - 1.0)
    var[count < 2] = np.nan
    return count, mean, var


def raster(scene, p: np.ndarray) -> np.ndarray:
    """Each vertex's position on the film in pixels of the crop window: where its camera ray left
    the sensor, found by projecting the vertex (`Sensor.sample_direction`'s uv).

    Args:
        scene: the scene (its first sensor). p: the vertices, 3 x N.

    Returns:
        N x 2 float64.
    """
    sensor = scene.sensors()[0]
    it = dr.zeros(mi.Interaction3f, p.shape[1])
    it.p = mi.Point3f(*(mi.Float(np.ascontiguousarray(p[i])) for i in range(3)))
    ds, _ = sensor.sample_direction(it, mi.Point2f(0.5, 0.5))
    # uv is in pixels of the crop window already (tests/denoise/test_expectation.py measures it on
    # a crop)
    return np.stack(
        [np.asarray(ds.uv.x, dtype=np.float64), np.asarray(ds.uv.y, dtype=np.float64)], -1
    )


def at_samples(buf: Buffer, d: np.ndarray, scene, g: guides.Guides, own: tuple) -> np.ndarray:
    """D at each camera sample's own film position, remodulated by its albedo, its emission added.

    Bilinear between the four nearest pixel centres that show the sample's own surface
    (`Field.lookup`), renormalised; the own pixel's D where none does or the projection fails.

    Args:
        buf: the buffer of means. d: D, H x W x 3 (the reflected part). scene: the scene.
        g: the pixel-footprint guides. own: (albedo, emission) at each sample's vertex, N x 3 each
            (`own_surface`).

    Returns:
        3 x N float32.
    """
    a = buf.arrays
    own_albedo, emission = own
    w = buf.width
    pix = a["pixel"].astype(np.int64)
    px, py = pix % w, pix // w
    found = a["slot"] >= 0
    if not found.any():  # the fallback everywhere: the sample's own pixel's D
        return np.ascontiguousarray(d[py, px].T.astype(np.float32))
    if "pos" in a:  # where the render loop put the sample (filtered buffers), in crop pixels
        uv = a["pos"].T.astype(np.float64) - np.asarray(buf.header["crop_offset"], np.float64)
    else:
        uv = raster(scene, a["p"])
    good = found & np.all(np.isfinite(uv), -1)
    good &= (np.floor(uv[:, 0]) == px) & (np.floor(uv[:, 1]) == py)
    diag = float(np.linalg.norm(np.asarray(scene.bbox().extents())))

    def vec(x, T):  # N x 3 or 3 x N host array -> Dr.Jit
        x = x if x.shape[0] == 3 else x.T
        return T(*(mi.Float(np.ascontiguousarray(x[i], np.float32)) for i in range(3)))
    near = mi.Bool(np.ascontiguousarray(good))
    fx = dr.select(near, mi.Float(np.ascontiguousarray(uv[:, 0], np.float32)), 0.5)
    fy = dr.select(near, mi.Float(np.ascontiguousarray(uv[:, 1], np.float32)), 0.5)
    # samples without a vertex keep their pixel's D as it is: no albedo (no remodulation),
    # no emission
    albedo = np.where(found[:, None], own_albedo, np.nan)
    emitted = np.where(found[:, None], emission, 0.0)
    out = Field(d, g, diag).at(
        fx,
        fy,
        vec(a["p"], mi.Point3f),
        vec(a["n"], mi.Vector3f),
        mi.UInt32(np.ascontiguousarray(pix, np.uint32)),
        vec(albedo, mi.Color3f),
        vec(emitted, mi.Color3f),
        mi.Bool(True),
        near,
    )
    dr.eval(out)  # one kernel for the three channels
    return np.ascontiguousarray(np.stack([np.asarray(out[i], np.float32) for i in range(3)]))


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
            return mi.Float(np.ascontiguousarray(a, np.float32).ravel())
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

    def lookup(self, fx, fy, ps, ns, pix, valid, near=None, albedo=None):
        """Sums over the four pixel centres around film position (fx, fy) of w D, w albedo and w;
        w: the bilinear weight where the pixel shows the vertex's own surface, else 0.

        Args:
            fx, fy: the film position (mi.Float, pixels of the crop window). ps, ns: the vertex's
                position (mi.Point3f) and normal (mi.Vector3f). pix: its pixel (mi.UInt32).
            valid: the lanes (mi.Bool). near: those whose position can be trusted (None: `valid`).
            albedo: the vertex's own albedo (mi.Color3f; None or not finite: pix's guide albedo).

        Returns:
            (sum of w D, sum of w albedo: mi.Vector3f each; sum of w: mi.Float). Own surface: the
            normal within ~18 degrees, the hit ~6 degrees of the tangent plane, albedo within 0.05.
        """
        near = valid if near is None else near
        w, h, get = self.w, self.h, self._get
        fx, fy = fx - 0.5, fy - 0.5
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

    def at(self, fx, fy, ps, ns, pix, own_albedo, emission, valid, near=None) -> mi.Color3f:
        """D for one vertex inside a kernel: interpolated (`lookup`), remodulated, emission added.

        Remodulated (REMODULATE): D x the vertex's own albedo / the albedo D was formed under (the
        guide albedo with the same weights), per channel, where both are positive. Design:
        docs/design/expectation_denoising.md.

        Args:
            fx, fy, ps, ns, pix, valid, near: as `lookup`'s. own_albedo: the vertex's albedo
                (mi.Color3f; NaN: left as it is). emission: its own emitted radiance (mi.Color3f).

        Returns:
            mi.Color3f: D (the own pixel's where no neighbour qualifies), remodulated, + emission.
        """
        acc, acc_a, wsum = self.lookup(fx, fy, ps, ns, pix, valid, near, own_albedo)
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


def own_surface(scene, a: dict) -> tuple[np.ndarray, np.ndarray]:
    """(albedo, emission) at each camera sample's own vertex, found again by a ray from just in
    front of the vertex (along wo) back onto it.

    Args:
        scene: the scene. a: the buffer's arrays (`p`, `wo`: 3 x N).

    Returns:
        (albedo, emission), N x 3 float64 each. albedo: as `guides.first_hit` forms it (through
        mirrors and glass); NaN where the vertex is not found again (`Field.at` then leaves the
        sample as it is). emission: the radiance the vertex emits towards wo (0 elsewhere and where
        not found); `attach` denoises the reflected part alone and adds it back per sample.
    """
    p = np.asarray(a["p"], np.float64)
    wo = np.asarray(a["wo"], np.float64)
    diag = float(np.linalg.norm(np.asarray(scene.bbox().extents())))
    eps = 1e-4 * max(diag, 1e-6)
    o = p + wo * eps
    ray = mi.Ray3f(
        mi.Point3f(*(mi.Float(np.ascontiguousarray(o[i], np.float32)) for i in range(3))),
        mi.Vector3f(*(mi.Float(np.ascontiguousarray(-wo[i], np.float32)) for i in range(3))),
    )
    ray.maxt = mi.Float(3.0 * eps)
    si = scene.ray_intersect(ray)
    dr.eval(si)  # measured: the chain after an evaluated hit costs half of one kernel doing both
    found = si.is_valid()
    alb, _ = guides.through_delta(scene, si, found)
    le = mi.Color3f(si.emitter(scene, found).eval(si, found))
    # one kernel: reading the channels one by one would trace the chain three times
    dr.eval(alb, le, found)
    hit = np.asarray(found, bool)
    albedo = np.stack([np.asarray(alb[i], np.float64) for i in range(3)], -1)
    albedo[~hit] = np.nan  # not found again: no correction for this sample
    emission = np.stack([np.asarray(le[i], np.float64) for i in range(3)], -1)
    emission[~hit] = 0.0
    return albedo, np.nan_to_num(emission)


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


def attach(
    buf: Buffer,
    scene,
    spp: int,
    seed: int,
    quality: str = "high",
    integrator=None,
    k: int = 0,
    uncertainty: float = 0.0,
):
    """Denoise the buffer's expectation: M formed, denoised into D, g's points placed.

    Args:
        buf, scene, spp, seed: the recorded buffer of means, its scene, samples per pixel, seed.
        quality: OIDN's. integrator: the render's (for k > 0). uncertainty: `spread`'s (> 0).
        k: 0: D kept at each camera sample in the buffer; > 0: g at k points (`coverage.points`).

    Returns:
        (D per pixel H x W x 3, None) for k = 0; (D, the points' buffer) for k > 0.

    Raises:
        UsageError: a buffer that does not store means.
    """
    if buf.stores != "mean":
        raise UsageError(
            "--denoise expectation needs a buffer of children means (direct or affine estimator)"
        )
    g = guides.first_hit(scene, spp, pass_seed(seed, 0), footprint="pixel")  # M's footprint
    own = _own(scene, buf)
    # the reflected part: each sample's own emission goes back in at_samples
    m = expectation(buf, own[1])
    d = oidn.denoise_oidn(m, g.albedo, g.normal, quality, guides.to_sensor(scene))
    d = below_resolution(d, m)
    header = {"method": "expectation", "quality": quality,
              "guides": "albedo and shading normal through specular chains (guides.first_hit)",
              "at_samples": "guided bilinear interpolation of D at each sample's film position"}
    if k:
        field = Field(d, g, float(np.linalg.norm(np.asarray(scene.bbox().extents()))))
        rel = spread(buf, own[1], uncertainty) if uncertainty > 0 else None
        if rel is not None:
            field.spread = mi.Float(np.ascontiguousarray(rel.ravel(), dtype=np.float32))
        cover = coverage_module.points(scene, integrator, field, k, seed)
        if rel is not None:  # per point, its pixel's: restyles average g over it too
            cover.arrays[SPREAD] = np.ascontiguousarray(
                rel.ravel()[cover.arrays["pixel"]], dtype=np.float32
            )
        cover.header["denoise"] = {**header, "coverage": k, "uncertainty": float(uncertainty)}
        if cover.filtered:  # the render loop splatted each point at its sample_pos, not the point's
            cover.image = image_of(cover)
        return d, cover
    buf.arrays[DENOISED] = at_samples(buf, d, scene, g, own)
    buf.header["denoise"] = header
    buf.device.clear()  # the Dr.Jit copy must pick up the denoised means
    return d, None


#: `uncertainty` by default: D's residual error as a fraction of the noisy M's standard error,
#: chosen on the Cornell box (BENCHMARKS.md denoise: 0.15, 0.2, 0.3, 0.45 and 1 tried)
UNCERTAINTY = 0.3


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
        buf: the buffer of means. emission: each sample's own emission, N x 3.
        uncertainty: the factor (`check_uncertainty`).

    Returns:
        H x W float64 in [0, 1]; it goes to 0 as the samples grow.
    """
    _, mean, var = _sample_moments(buf, reflected(buf, emission).mean(1, keepdims=True))
    mean, var_of_mean = mean[:, 0], np.nan_to_num(var[:, 0])  # below 2 samples: 0
    floor = 1e-3 * max(float(np.abs(mean).mean()), 1e-12)
    rel2 = (var_of_mean / np.maximum(np.abs(mean), floor) ** 2).reshape(buf.height, buf.width)
    padded = np.pad(rel2, 1, mode="edge")
    h, w = rel2.shape
    local = sum(padded[dy:dy + h, dx:dx + w] for dy in range(3) for dx in range(3)) / 9.0
    return np.minimum(uncertainty * np.sqrt(local), 1.0)


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
    `variance`; NaN below 2 samples. D, where the buffer holds it, is set aside meanwhile.

    Args:
        buf: the buffer.

    Returns:
        H x W x 3 float32.
    """
    slots = prepare_slots(buf, slots_for(buf))
    held = buf.arrays.pop(DENOISED, None)
    buf.device.clear()
    try:
        v = sample_values(buf, slots)
        vals = np.stack([np.asarray(v[c], dtype=np.float64) for c in range(3)], axis=-1)
    finally:
        if held is not None:
            buf.arrays[DENOISED] = held
        buf.device.clear()
    var = _sample_moments(buf, vals, np.ones(buf.samples, bool))[2]  # every sample, vertex or not
    return var.reshape(buf.height, buf.width, 3).astype(np.float32)


def render_denoised_expectation(
    scene,
    integrator,
    spp: int,
    seed: int = 0,
    quality: str = "high",
    callback: Callable[[Progress], None] | None = None,
    max_samples: int = MAX_SAMPLES,
    label: str = "",
    coverage: int | str = "auto",
    uncertainty: float = UNCERTAINTY,
    lanes_per_pass: int = LANES_PER_PASS,
    pass_spp: int | None = None,
) -> tuple[np.ndarray, Buffer]:
    """The denoised-expectation render: `ExpectationJob`'s passes, then its `finish`.

    Args:
        scene, integrator, spp, seed, quality, max_samples, label, coverage, uncertainty,
            lanes_per_pass, pass_spp: as `ExpectationJob`'s. callback: called with each `Progress`.

    Returns:
        (the image, H x W x 3 float32; its buffer, whose `image` is the noisy render). With coverage
        k > 0 the buffer is the coverage points' (`buf.source`: the camera samples').

    Raises:
        UsageError: a refusal of `ExpectationJob` or of its `finish`.
    """
    job = ExpectationJob(
        scene,
        integrator,
        spp,
        seed,
        quality,
        max_samples,
        label,
        coverage,
        uncertainty,
        lanes_per_pass,
        pass_spp,
    )
    for prog, _ in job.passes():
        if callback is not None:
            callback(prog)
    return job.finish()


class ExpectationJob:
    """A denoised-expectation render in two steps, for callers that show and cancel passes:
    `passes()` records the noisy buffer (`buffer`), `finish()` denoises it and applies g.

    Args:
        scene, integrator: what to render (its error AOVs come from the buffer, `aovs`). spp, seed:
            the render's. quality: OIDN's. max_samples: the buffer's cap. label: the scene's label.
        coverage: points per pixel where g meets D (`coverage.resolve_k`). uncertainty: `spread`'s.
        lanes_per_pass, pass_spp: the pass split, as `pipeline.passes`'s.

    Raises:
        UsageError: no pyoidn, a bad quality, coverage or uncertainty, or an unsupported render
            (`check_expectation`), refused when the job is made, before anything renders.
    """

    def __init__(
        self,
        scene,
        integrator,
        spp: int,
        seed: int = 0,
        quality: str = "high",
        max_samples: int = MAX_SAMPLES,
        label: str = "",
        coverage: int | str = "auto",
        uncertainty: float = UNCERTAINTY,
        lanes_per_pass: int = LANES_PER_PASS,
        pass_spp: int | None = None,
    ):
        oidn.require()
        oidn.check_quality(quality)
        check_expectation(integrator)
        w, h = (int(v) for v in scene.sensors()[0].film().crop_size())
        self.k = coverage_module.resolve_k(coverage, w, h, max_samples)
        self.uncertainty = check_uncertainty(uncertainty)
        # the buffer records without them; `aovs` below derives them from it
        if integrator.settings.aovs:
            integrator = StylizedIntegrator.from_values({**integrator.values, "aovs": False})
        self.scene, self.integrator, self.spp, self.seed, self.quality = (
            scene,
            integrator,
            spp,
            seed,
            quality,
        )
        self.max_samples, self.label, self.lanes, self.pass_spp = (
            max_samples,
            label,
            lanes_per_pass,
            pass_spp,
        )
        #: the noisy buffer of the passes recorded so far (None before the first)
        self.buffer: Buffer | None = None

    def passes(self) -> Iterator[tuple[Progress, Buffer]]:
        for prog, buf in record(
            self.scene,
            self.integrator,
            self.spp,
            self.seed,
            self.label or scene_label(None),
            self.max_samples,
            self.lanes,
            pass_spp=self.pass_spp,
        ):
            buf.image = prog.image
            self.buffer = buf
            yield prog, buf

    def finish(self) -> tuple[np.ndarray, Buffer]:
        """(the denoised image, the buffer that restyles to it) from the recorded buffer; one-line
        UsageError if not every pixel has a camera sample yet (a render cancelled in its first round
        of tiles)."""
        buf = self.buffer
        if buf is None or buf.spp < 1:
            raise UsageError("nothing to denoise: no pass of the render finished")
        _, cover = attach(
            buf,
            self.scene,
            buf.spp,
            self.seed,
            self.quality,
            self.integrator,
            self.k,
            self.uncertainty,
        )
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
    "check_expectation",
    "expectation",
    "image_of",
    "noisy_variance",
    "aovs",
    "DENOISED",
]
