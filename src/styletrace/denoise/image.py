"""Denoising the final image: `--denoise image`, the baseline.

    image, noisy, aovs = render_denoised_image(scene, integrator, spp=16, seed=0, quality="high")

The stylized image is rendered as usual (`pipeline.passes`) and OIDN denoises it with the same
albedo and normal guides as `--denoise expectation`. Every mode of the renderer works (it is a
post-process), but a step style's band flips are edges to the denoiser, which keeps them
(docs/denoise.md, BENCHMARKS.md).
"""
from __future__ import annotations

from typing import Callable

import numpy as np

from styletrace.denoise import guides, oidn
from styletrace.pipeline.passes import LANES_PER_PASS, Progress, pass_seed, passes


def render_denoised_image(scene, integrator, spp: int, seed: int = 0, quality: str = "high",
           callback: Callable[[Progress], None] | None = None, lanes_per_pass: int = LANES_PER_PASS,
           pass_spp: int | None = None) -> tuple[np.ndarray, np.ndarray, dict | None]:
    """Render in passes (`pipeline.passes.passes`), then denoise the final image.

    Args:
        scene, integrator: what to render. spp: samples per pixel. seed: the render's seed.
        quality: OIDN's "high", "balanced" or "fast". callback: called with each pass's `Progress`.
        lanes_per_pass, pass_spp: the pass split, as `pipeline.passes`'s.

    Returns:
        (denoised image, noisy image, AOVs or None: `finish_denoised_image`), H x W x 3 float32.

    Raises:
        UsageError: no pyoidn, a bad quality, or a refusal of the pass loop.
    """
    oidn.require()
    oidn.check_quality(quality)
    prog = None
    for prog in passes(
        scene, integrator, spp, seed, lanes_per_pass=lanes_per_pass, pass_spp=pass_spp
    ):
        if callback is not None:
            callback(prog)
    return finish_denoised_image(scene, prog, seed, quality)


def finish_denoised_image(
    scene, prog: Progress, seed: int = 0, quality: str = "high"
) -> tuple[np.ndarray, np.ndarray, dict | None]:
    """The denoised result of the passes' last progress (also the finished passes of a stopped
    render: the guides take as many camera samples per pixel as they did).

    Args:
        scene: the scene rendered. prog: the last finished pass's `Progress`.
        seed: the render's seed (the guides use its first pass's). quality: OIDN's quality.

    Returns:
        (denoised, noisy, aovs), H x W x 3 float32 images; aovs None, or with aovs=True the noisy
        render's renamed (`noisy_variance`, `noisy_bias`, `children`) and `denoise_change`
        (denoised - noisy).
    """
    noisy = np.asarray(prog.image, dtype=np.float32)
    g = guides.first_hit(scene, prog.spp_done, pass_seed(seed, 0))
    out = oidn.denoise_oidn(noisy, g.albedo, g.normal, quality, guides.to_sensor(scene))
    errs = prog.aovs
    if errs is not None:
        errs = {
            "noisy_variance": errs["variance"],
            "noisy_bias": errs["bias"],
            "children": errs["children"],
            "denoise_change": out - noisy[..., :3],
        }
    return out, noisy, errs


__all__ = ["render_denoised_image", "finish_denoised_image"]
