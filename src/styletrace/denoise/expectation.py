"""Denoising the expectation before the style: `--denoise expectation`.

    image, buf = render(scene, integrator, spp=16, seed=0, quality="high")

Per camera sample the renderer records (as `lookdev.record` does for an expectation buffer) the stylized
vertex, the radiance before it and the mean of its n children, the estimate of E[L] there. Per pixel the
means of the camera samples that found a stylized vertex are averaged: the pixel's estimate of the
expectation M. M is denoised by OIDN with first-hit albedo and normal guides (`guides`, `oidn`), giving D,
and every such camera sample then takes its own style slot's g of D (at its own vertex: hatching's lines
and per-object styles stay per sample): value = g(D[pixel], vertex); pixel = mean of its samples. D is
kept in the buffer (`denoised_mean`, 3 x pixels), so a restyle of the buffer (`lookdev.restyle`) styles D
too, at the usual milliseconds.

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

import numpy as np  # noqa: E402

from .. import api  # noqa: E402
from ..errors import UsageError  # noqa: E402
from ..lookdev.buffer import MAX_SAMPLES, Buffer  # noqa: E402
from ..lookdev.record import record, scene_label  # noqa: E402
from ..lookdev.restyle import RESTYLABLE_ESTIMATORS, accumulate, prepare, sample_values, slots_for  # noqa: E402
from ..plugins import settings as S  # noqa: E402
from . import guides, oidn  # noqa: E402

#: the buffer array holding the denoised expectation per pixel (3 x H*W, row-major)
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


def attach(buf: Buffer, scene, spp: int, seed: int, quality: str = "high") -> np.ndarray:
    """Denoise the buffer's expectation and keep it in the buffer (restyles then style it); returns D."""
    if buf.stores != "mean":
        raise UsageError("--denoise expectation needs a buffer of children means (direct or affine estimator)")
    albedo, normal = guides.first_hit(scene, spp, api.pass_seed(seed, 0))
    d = oidn.run(expectation(buf), albedo, normal, quality, guides.to_sensor(scene))
    buf.arrays[DENOISED] = np.ascontiguousarray(d.reshape(-1, 3).T.astype(np.float32))
    buf.header["denoise"] = {"method": "expectation", "quality": quality,
                             "guides": "first-hit albedo and shading normal, Mitsuba aov integrator"}
    buf.device.clear()  # the Dr.Jit copy must pick up the denoised means
    return d


def image_of(buf: Buffer) -> np.ndarray:
    """The buffer's image with its recorded styles (denoised where the buffer holds D)."""
    slots = prepare(buf, slots_for(buf))
    return np.asarray(accumulate(buf, sample_values(buf, slots)), dtype=np.float32).reshape(buf.height, buf.width, 3)


def noisy_variance(buf: Buffer) -> np.ndarray:
    """The variance of each pixel's *undenoised* estimate from its camera samples' values, (mean of squares -
    squared mean) / (spp - 1), as `api.Progress.aovs` defines `variance`; NaN below 2 samples."""
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
           callback: Callable[[api.Progress], None] | None = None, max_samples: int = MAX_SAMPLES,
           label: str = "") -> tuple[np.ndarray, Buffer]:
    """The denoised-expectation image (H x W x 3 float32) and its buffer (`buf.image`: the noisy render)."""
    oidn.require()
    oidn.check_quality(quality)
    check(integrator)
    if integrator.settings.aovs:  # the buffer records without them; `aovs` below derives them from it
        integrator = api.make_integrator_from({**integrator.values, "aovs": False})
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
