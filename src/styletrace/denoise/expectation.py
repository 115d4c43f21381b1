"""Denoising the expectation before the style: `--denoise expectation`.

    image, buf = render(scene, integrator, spp=16, seed=0, quality="high")

Per camera sample the renderer records (as `lookdev.record` does for an expectation buffer) the stylized
vertex, the radiance before it and the mean of its n children, the estimate of E[L] there. Per pixel the
means of the camera samples that found a stylized vertex are averaged: the pixel's estimate of the
expectation M. M is denoised by OIDN with first-hit albedo and normal guides (`guides`, `oidn`), giving D,
and every such camera sample then takes its own style slot's g of D interpolated at its own film position
(`at_samples`: guided bilinear, so a threshold crossing is placed within the pixel) at its own vertex
(hatching's lines and per-object styles stay per sample): value = g(D(sample), vertex); pixel = mean of its
samples. D at the samples is kept in the buffer (`denoised_mean`, 3 x samples, in place of the children's
means when restyling), so a restyle of the buffer (`lookdev.restyle`) styles D too, at the usual milliseconds.

Why before g: a step style (cel, hatching) turns the noise of M into band flips, which a denoiser of the
final image sees as edges and keeps; the noise of M itself is the smooth Monte Carlo noise denoisers are
trained on. The price is the denoiser's bias (docs/denoise.md).

Parameters: `quality` OIDN's "high" (default), "balanced" or "fast"; `max_samples` the buffer's cap
(`lookdev.buffer.MAX_SAMPLES`, 4,194,304 camera samples).

Supported: `first_hit` with the integrator's style and per-object (`styled`) styles, the `direct` and
`affine` estimators, fixed counts n. Refused, one line each (`check`): first_object_hit, first_n_hits /
stylize_depth > 1, lines, reuse, adaptive counts, the unbiased estimators, the expansion pass, per-sample
styles (acp), Ray (cluster=), films other than rgb with a box filter (the buffer's own conditions).
"""
from __future__ import annotations

from typing import Callable

from ..jit import backend

backend()

import drjit as dr  # noqa: E402
import mitsuba as mi  # noqa: E402
import numpy as np  # noqa: E402

from ..pipeline.passes import Progress, pass_seed  # noqa: E402
from ..errors import UsageError  # noqa: E402
from ..lookdev.buffer import MAX_SAMPLES, Buffer  # noqa: E402
from ..lookdev.record import record, scene_label  # noqa: E402
from ..lookdev.restyle import RESTYLABLE_ESTIMATORS, accumulate, prepare, sample_values, slots_for  # noqa: E402
from ..config import settings as S  # noqa: E402
from ..kernel.integrator import StylizedIntegrator  # noqa: E402
from . import guides, oidn  # noqa: E402

#: the buffer array holding the denoised expectation at each camera sample (3 x samples, as `mean`)
DENOISED = "denoised_mean"


def check(integrator) -> None:
    """Refuse, in one line, what the expectation denoiser does not support (see the module docstring)."""
    s = integrator.settings
    why = None
    if s.stylize == "first_object_hit":
        why = ("stylize=first_object_hit: its stylized vertex may lie behind a mirror or glass, where the "
               "first-hit guides describe another surface; use first_hit or --denoise image")
    elif s.stylize == "first_n_hits" or s.stylize_depth != 1:
        why = ("stylize=first_n_hits: nested levels have no per-pixel expectation to denoise (the inner levels' "
               "vertices are not the pixel's); use first_hit or --denoise image")
    elif s.lines is not None:
        why = "feature lines: lines replace radiance inside the estimate; use --denoise image"
    elif s.reuse != "off":
        why = f"reuse={s.reuse}: denoising and reuse both filter the expectation; use one"
    elif s.expansion_pass:
        why = "expansion_pass: it serves the series estimators, which denoising replaces by direct application"
    elif s.slot.estimator not in RESTYLABLE_ESTIMATORS:
        why = (f"estimator '{s.slot.estimator}': the denoised expectation is styled by direct application; "
               f"use direct or affine")
    elif S.adaptive(s.inner):
        why = "adaptive counts n0:n_max: give a fixed count (the denoiser does the averaging)"
    elif s.style.per_sample:
        why = f"style '{s.style.name}': it applies g to every child, there is no expectation to denoise"
    if why is not None:
        raise UsageError(f"--denoise expectation cannot render {why}")


def expectation(buf: Buffer) -> np.ndarray:
    """M: per pixel, the mean of its camera samples' children means where a stylized vertex was found
    (0 where none was), H x W x 3 float32."""
    a = buf.arrays
    found = a["slot"] >= 0
    pix = a["pixel"][found].astype(np.int64)
    size = buf.width * buf.height
    count = np.bincount(pix, minlength=size).astype(np.float64)
    out = np.stack([np.bincount(pix, weights=a["mean"][c][found].astype(np.float64), minlength=size)
                    for c in range(3)], axis=-1) / np.maximum(count, 1.0)[:, None]
    return out.reshape(buf.height, buf.width, 3).astype(np.float32)


def raster(scene, p: np.ndarray) -> np.ndarray:
    """Each vertex's position on the film in pixels of the crop window (N x 2): where its camera ray left the
    sensor, found by projecting the vertex (`Sensor.sample_direction`'s uv)."""
    sensor = scene.sensors()[0]
    it = dr.zeros(mi.Interaction3f, p.shape[1])
    it.p = mi.Point3f(*(mi.Float(np.ascontiguousarray(p[i])) for i in range(3)))
    ds, _ = sensor.sample_direction(it, mi.Point2f(0.5, 0.5))
    off = np.asarray([int(v) for v in sensor.film().crop_offset()], dtype=np.float64)
    return np.stack([np.asarray(ds.uv.x, dtype=np.float64), np.asarray(ds.uv.y, dtype=np.float64)], -1) - off


def at_samples(buf: Buffer, d: np.ndarray, scene, albedo, normal, position) -> np.ndarray:
    """D at each camera sample's own film position (3 x N): bilinear between the four nearest pixel centres,
    keeping only the pixels that show the sample's own surface (normal within ~18 degrees, the pixel's
    first hit within ~6 degrees of the sample's tangent plane, albedo within 0.05), renormalised; the
    sample's own pixel's D where none qualifies or the projection fails (a camera model without one).

    Why: at a cel threshold the reference's band boundary runs through pixels, and its camera samples fall
    on either side of it; D constant per pixel puts the whole pixel on one side. Interpolating D at the
    sample's position places the boundary to a fraction of a pixel (BENCHMARKS.md: ~18% lower MSE on the
    Cornell box at n = 32; the choice was made there). The guide tests keep the interpolation from mixing
    surfaces across geometric edges and texture edges."""
    a = buf.arrays
    w, h = buf.width, buf.height
    pix = a["pixel"].astype(np.int64)
    px, py = pix % w, pix // w
    own = d[py, px].astype(np.float64)
    found = a["slot"] >= 0
    if not found.any():
        return np.ascontiguousarray(own.T.astype(np.float32))
    uv = raster(scene, a["p"])
    good = found & np.all(np.isfinite(uv), -1)
    good &= (np.floor(uv[:, 0]) == px) & (np.floor(uv[:, 1]) == py)
    ns, ps = a["n"].T.astype(np.float64), a["p"].T.astype(np.float64)
    a_s = albedo[py, px]
    diag = float(np.linalg.norm(np.asarray(scene.bbox().extents())))
    fx, fy = uv[:, 0] - 0.5, uv[:, 1] - 0.5
    x0, y0 = np.floor(np.where(good, fx, 0)).astype(np.int64), np.floor(np.where(good, fy, 0)).astype(np.int64)
    acc, acc_a, wsum = np.zeros_like(own), np.zeros_like(own), np.zeros(len(pix))
    for dy in (0, 1):
        for dx in (0, 1):
            qx, qy = np.clip(x0 + dx, 0, w - 1), np.clip(y0 + dy, 0, h - 1)
            wt = np.clip(1 - np.abs(fx - (x0 + dx)), 0, 1) * np.clip(1 - np.abs(fy - (y0 + dy)), 0, 1)
            gap = position[qy, qx] - ps
            same = (np.sum(normal[qy, qx] * ns, -1) > 0.95)
            same &= np.abs(np.sum(gap * ns, -1)) <= 0.1 * np.linalg.norm(gap, axis=-1) + 1e-5 * diag
            same &= np.abs(albedo[qy, qx] - a_s).max(-1) <= 0.05
            wt = np.where(good & same, wt, 0.0)
            acc += wt[:, None] * d[qy, qx]
            acc_a += wt[:, None] * albedo[qy, qx]
            wsum += wt
    out = np.where((wsum > 1e-6)[:, None], acc / np.maximum(wsum, 1e-12)[:, None], own)
    if REMODULATE:
        # the guide albedo with the same weights: what albedo the interpolated D was formed under
        mixed = np.where((wsum > 1e-6)[:, None], acc_a / np.maximum(wsum, 1e-12)[:, None], a_s)
        out = remodulate(out, mixed, sample_albedo(scene, a), found)
    return np.ascontiguousarray(out.T.astype(np.float32))


#: rescale D at each camera sample by its own albedo over the pixel's (`remodulate`)
REMODULATE = True


def sample_albedo(scene, a: dict) -> np.ndarray:
    """The albedo guide at each camera sample's own vertex (N x 3): the BSDF's diffuse reflectance at p, found
    by a ray from just in front of the vertex (along wo) back onto it; 1 where a surface has none (the
    guides' rule for specular surfaces), NaN where the ray does not find it again (`remodulate` then leaves
    the sample as it is)."""
    p = np.asarray(a["p"], np.float64)
    wo = np.asarray(a["wo"], np.float64)
    diag = float(np.linalg.norm(np.asarray(scene.bbox().extents())))
    eps = 1e-4 * max(diag, 1e-6)
    o = p + wo * eps
    ray = mi.Ray3f(mi.Point3f(*(mi.Float(np.ascontiguousarray(o[i], np.float32)) for i in range(3))),
                   mi.Vector3f(*(mi.Float(np.ascontiguousarray(-wo[i], np.float32)) for i in range(3))))
    ray.maxt = mi.Float(3.0 * eps)
    si = scene.ray_intersect(ray)
    alb = si.bsdf().eval_diffuse_reflectance(si, si.is_valid())
    out = np.stack([np.asarray(alb[i], np.float64) for i in range(3)], -1)
    hit = np.asarray(si.is_valid(), bool)
    out[hit & np.all(out <= 0.0, -1)] = 1.0
    out[~hit] = np.nan  # not found again: no correction for this sample
    return out


def remodulate(d: np.ndarray, mixed: np.ndarray, own: np.ndarray, found: np.ndarray) -> np.ndarray:
    """D x own albedo / the albedo D was formed under, per channel, for samples with a vertex.

    Why: a pixel on a texture edge averages two albedos into its M, and so into D (E[L] of a diffuse surface
    is albedo x irradiance); its camera samples on the dark side would take the bright side's share and the
    other way round. The irradiance D / albedo varies slowly across the edge, so each sample takes its
    own albedo times it. Where the albedos agree (no texture edge in the pixel) the factor is 1."""
    ok = found[:, None] & np.isfinite(own) & (mixed > 1e-4) & (own > 0)
    factor = np.where(ok, own / np.where(ok, mixed, 1.0), 1.0)
    return d * factor


#: OIDN's output is trusted down to this fraction of the image's mean brightness (see `below_resolution`)
RESOLUTION = 1e-3


def below_resolution(d: np.ndarray, m: np.ndarray) -> np.ndarray:
    """D with the pixels darker than RESOLUTION x the mean brightness of M set to 0.

    Why: where the expectation is about 0 (a mirror reflecting the empty space behind the camera), OIDN leaks
    a little of the neighbours' light, with a random hue. Chroma-preserving styles (cel: I level / brightness(I))
    amplify that hue into saturated speckle, where the reference, whose I is 0 or neutral there, shows the
    style's plain level. Below the denoiser's resolution the value carries no information: 0 it is."""
    lum = d.mean(-1)
    scale = float(np.mean(m.mean(-1)))
    out = d.copy()
    out[lum < RESOLUTION * scale] = 0.0
    return np.maximum(out, 0.0)


def attach(buf: Buffer, scene, spp: int, seed: int, quality: str = "high") -> np.ndarray:
    """Denoise the buffer's expectation and keep it, at each camera sample, in the buffer (restyles then
    style it); returns D per pixel (H x W x 3)."""
    if buf.stores != "mean":
        raise UsageError("--denoise expectation needs a buffer of children means (direct or affine estimator)")
    albedo, normal, position = guides.first_hit(scene, spp, pass_seed(seed, 0), position=True)
    m = expectation(buf)
    d = oidn.run(m, albedo, normal, quality, guides.to_sensor(scene))
    d = below_resolution(d, m)
    buf.arrays[DENOISED] = at_samples(buf, d, scene, albedo, normal, position)
    buf.header["denoise"] = {"method": "expectation", "quality": quality,
                             "guides": "first-hit albedo and shading normal, Mitsuba aov integrator",
                             "at_samples": "guided bilinear interpolation of D at each camera sample's film position"}
    buf.device.clear()  # the Dr.Jit copy must pick up the denoised means
    return d


def image_of(buf: Buffer) -> np.ndarray:
    """The buffer's image with its recorded styles (denoised where the buffer holds D)."""
    slots = prepare(buf, slots_for(buf))
    return np.asarray(accumulate(buf, sample_values(buf, slots)), dtype=np.float32).reshape(buf.height, buf.width, 3)


def noisy_variance(buf: Buffer) -> np.ndarray:
    """The variance of each pixel's *undenoised* estimate from its camera samples' values, (mean of squares -
    squared mean) / (spp - 1), as `pipeline.passes.Progress.aovs` defines `variance`; NaN below 2 samples."""
    slots = prepare(buf, slots_for(buf))
    held = buf.arrays.pop(DENOISED, None)
    buf.device.clear()
    try:
        v = sample_values(buf, slots)
        vals = np.stack([np.asarray(v[c], dtype=np.float64) for c in range(3)], axis=-1)
    finally:
        if held is not None:
            buf.arrays[DENOISED] = held
        buf.device.clear()
    pix = buf.arrays["pixel"].astype(np.int64)
    size = buf.width * buf.height
    n = np.bincount(pix, minlength=size).astype(np.float64)[:, None]
    s1 = np.stack([np.bincount(pix, weights=vals[:, c], minlength=size) for c in range(3)], -1)
    s2 = np.stack([np.bincount(pix, weights=vals[:, c] ** 2, minlength=size) for c in range(3)], -1)
    with np.errstate(divide="ignore", invalid="ignore"):
        mean = s1 / n
        var = np.maximum(s2 / n - mean * mean, 0.0) / (n - 1.0)
    var[n[:, 0] < 2] = np.nan
    return var.reshape(buf.height, buf.width, 3).astype(np.float32)


def render(scene, integrator, spp: int, seed: int = 0, quality: str = "high",
           callback: Callable[[Progress], None] | None = None, max_samples: int = MAX_SAMPLES,
           label: str = "") -> tuple[np.ndarray, Buffer]:
    """The denoised-expectation image (H x W x 3 float32) and its buffer (`buf.image`: the noisy render)."""
    oidn.require()
    oidn.check_quality(quality)
    check(integrator)
    if integrator.settings.aovs:  # the buffer records without them; `aovs` below derives them from it
        integrator = StylizedIntegrator.from_values({**integrator.values, "aovs": False})
    buf = None
    for prog, buf in record(scene, integrator, spp, seed, label or scene_label(None), max_samples):
        buf.image = prog.image
        if callback is not None:
            callback(prog)
    attach(buf, scene, spp, seed, quality)
    return image_of(buf), buf


def aovs(buf: Buffer, image: np.ndarray) -> dict[str, np.ndarray]:
    """Honest error AOVs of a denoised-expectation render (docs/denoise.md): the variance of the pixel
    *before* denoising (not the denoised pixel's error, which no per-pixel statistic here measures), the
    children per camera sample, and what denoising changed (denoised - noisy image)."""
    n = max(int(s["inner"]) for s in buf.header["slots"])
    return {"noisy_variance": noisy_variance(buf),
            "children": np.full((buf.height, buf.width), float(n), dtype=np.float32),
            "denoise_change": (np.asarray(image, np.float32) - np.asarray(buf.image, np.float32)[..., :3])}


__all__ = ["render", "attach", "check", "expectation", "image_of", "noisy_variance", "aovs", "DENOISED"]
