"""Denoising the final image: `--denoise image`, the baseline.

    image, noisy, aovs = render_denoised_image(Shot(scene, integrator, spp=16, seed=0))

The stylized image is rendered as usual (`pipeline.passes`) and OIDN denoises it with the same
albedo and normal guides as `--denoise expectation`. Every mode of the renderer works (it is a
post-process), but a step style's band flips are edges to the denoiser, which keeps them
(docs/denoise.md, BENCHMARKS.md).

On a film whose filter is not a box, the passes keep each camera sample in its own pixel
(`in_pixels`: `run_passes(in_pixels=True)`), OIDN denoises that image with guides of the same
footprint, and the film's filter is applied to the denoised image (`film_filter.filtered_pixels`):
a tent or gaussian filter would spread each sample over neighbouring pixels, and OIDN keeps noise
so correlated as texture (docs/look.md, "Clean where the light is hard").
"""
from __future__ import annotations

from typing import Callable

import numpy as np

from styletrace.denoise import oidn
from styletrace.errors import UsageError
from styletrace.kernel import guides
from styletrace.lookdev.film_filter import filtered_pixels
from styletrace.pipeline.denoising import Denoising
from styletrace.pipeline.passes import PassSplit, Progress, Shot, pass_seed, run_passes


def render_denoised_image(shot: Shot, denoising: Denoising = Denoising("image"),
                          split: PassSplit = PassSplit(),
                          callback: Callable[[Progress], None] | None = None
                          ) -> tuple[np.ndarray, np.ndarray, dict | None]:
    """Render in passes (`pipeline.passes.run_passes`), then denoise the final image.

    Args:
        shot: what to render, its camera samples per pixel and seed.
        denoising: OIDN's quality ("high", "balanced" or "fast") and the footprint, "pixel" (the
            module doc) or "film" (the film's image as it is); its method is not read.
        split: the pass split (`pipeline.passes.PassSplit`).
        callback: called with each pass's `Progress`.

    Returns:
        (denoised image, noisy image, AOVs or None: `finish_denoised_image`), H x W x 3 float32.

    Raises:
        UsageError: no pyoidn, a bad quality or footprint, or a refusal of the pass loop.
    """
    oidn.require()
    oidn.check_quality(denoising.quality)
    pixels = (check_footprint(denoising.footprint) == "pixel"
              and in_pixels(shot.scene, shot.integrator))
    prog = None
    for prog in run_passes(shot, split, in_pixels=pixels):
        if callback is not None:
            callback(prog)
    return finish_denoised_image(shot.scene, prog, shot.seed, denoising.quality)


#: what the image denoiser denoises: each pixel's own samples, or the film's image as it is
FOOTPRINTS = ("pixel", "film")


def check_footprint(footprint) -> str:
    """`footprint` if it is one of FOOTPRINTS.

    Raises:
        UsageError: any other value (one line).
    """
    if footprint not in FOOTPRINTS:
        raise UsageError(f"bad value {footprint!r} for denoise_footprint: expected one of "
                         f"{', '.join(FOOTPRINTS)}")
    return footprint


def in_pixels(scene, integrator) -> bool:
    """Whether the image denoiser's passes keep each sample in its pixel (the module doc): a film
    whose filter is not a box, and a `stylized` integrator whose `sample` is its whole render
    (not reuse=pixels) without error AOVs (they describe the film's image).

    Args:
        scene: the scene (its first sensor's film). integrator: the render's integrator.

    Returns:
        True where `run_passes(in_pixels=True)` applies.
    """
    from styletrace.kernel.integrator import StylizedIntegrator
    if scene.sensors()[0].film().rfilter().is_box_filter():
        return False
    if not isinstance(integrator, StylizedIntegrator):
        return False
    s = integrator.settings
    return s.reuse == "off" and not integrator.aov_names()


def finish_denoised_image(
    scene, prog: Progress, seed: int = 0, quality: str = "high", history=None
) -> tuple[np.ndarray, np.ndarray, dict | None]:
    """The denoised result of the passes' last progress (also the finished passes of a stopped
    render: the guides take as many camera samples per pixel as they did).

    Args:
        scene: the scene rendered. prog: the last finished pass's `Progress`.
        seed: the render's seed (the guides use its first pass's). quality: OIDN's quality.
        history: the frames' `denoise.temporal.History`: OIDN denoises the noisy image blended
            with it (its `blend`; the caller commits), or None.

    Returns:
        (denoised, noisy, aovs), H x W x 3 float32 images; aovs None, or with aovs=True the noisy
        render's renamed (`noisy_variance`, `noisy_bias`, `children`) and `denoise_change`
        (denoised - noisy).
    """
    noisy = np.asarray(prog.image, dtype=np.float32)
    pixels = getattr(prog, "in_pixels", False)
    g = guides.first_hit(scene, prog.spp_done, pass_seed(seed, 0),
                         footprint="pixel" if pixels else "film")
    before = noisy
    if history is not None:  # the pixels' variance where the error AOVs give it, else local
        var = None if prog.aovs is None else prog.aovs["variance"]
        before = noisy.copy()
        before[..., :3] = history.blend(noisy[..., :3], var, prog.spp_done)
    out = oidn.denoise_oidn(before, g.albedo, g.normal, quality, guides.to_sensor(scene))
    if pixels:
        out = filtered_pixels(out, scene.sensors()[0].film().rfilter())
    errs = prog.aovs
    if errs is not None:
        errs = {
            "noisy_variance": errs["variance"],
            "noisy_bias": errs["bias"],
            "children": errs["children"],
            "denoise_change": out - noisy[..., :3],
        }
    return out, noisy, errs


def denoise_like(scene, image: np.ndarray, spp: int, seed: int, quality: str,
                 cache: dict | None = None) -> np.ndarray:
    """`image` denoised as `finish_denoised_image` denoises the film's image of `spp` camera
    samples per pixel: OIDN with the guides of as many (a restyle of a recorded buffer, denoised as
    the render that recorded it was).

    Args:
        scene: the scene rendered. image: H x W x 3, the film's image. spp: its camera samples per
            pixel. seed: the render's seed. quality: OIDN's quality.
        cache: {spp: guides} kept between calls (the guides are traced once per spp), or None.

    Returns:
        H x W x 3 float32.
    """
    g = None if cache is None else cache.get(spp)
    if g is None:
        g = guides.first_hit(scene, spp, pass_seed(seed, 0), footprint="film")
        if cache is not None:
            cache.clear()  # only the newest count serves
            cache[spp] = g
    return oidn.denoise_oidn(np.asarray(image, np.float32), g.albedo, g.normal, quality,
                             guides.to_sensor(scene))


__all__ = ["render_denoised_image", "finish_denoised_image", "denoise_like", "in_pixels",
           "check_footprint",
           "FOOTPRINTS"]
