"""F12 with Denoise on: the render settings' `denoise` ("expectation" or "image") through styletrace's denoisers.

- expectation (`denoise.expectation.Job`): the passes record the expectation buffer; after the last pass (or a
  cancel) the expectation is denoised and the style applied. With Record buffer on, the buffer kept for restyling
  is the denoised one, so a style change restyles to what a denoised F12 with the new value gives.
- image (`denoise.image.denoise`): the passes as usual, then OIDN on the image. Record buffer is refused with it:
  restyles of a noisy buffer would not be the denoised image F12 showed.
Both are the command line's (`styletrace render FILE.xml --denoise ... --pass-spp N`: the same image for the same
seed and pass split). Without the `denoise` extra (pyoidn), F12 refuses in one line naming it.
"""
from __future__ import annotations

from typing import Iterator

import numpy as np

from .. import api
from ..errors import UsageError
from . import pipeline


class _Expectation:
    """The job and the buffer recorded so far."""

    def __init__(self, job):
        self.job, self.buffer = job, None


def prepare(sc, integ, settings):
    """None without denoising; else what `passes` and `finish` need, after every refusal (one line each)."""
    if settings.denoise == "off":
        return None
    from ..denoise import oidn
    oidn.require()
    oidn.check_quality(settings.denoise_quality)
    if settings.denoise == "image":
        if settings.record_buffer:
            raise UsageError("Record buffer with Denoise 'image': restyles of the noisy buffer would not be the "
                             "denoised image; use Denoise 'expectation' (its buffer keeps the denoised expectation)")
        return settings.denoise
    from ..denoise import expectation
    return _Expectation(expectation.Job(sc, integ, settings.spp, settings.seed, settings.denoise_quality,
                                        label="<blender>", pass_spp=settings.pass_spp))


def passes(job, sc, integ, settings) -> Iterator[api.Progress]:
    """F12's passes: the expectation job's (recording its buffer), or the ordinary ones for image denoising."""
    if not isinstance(job, _Expectation):
        yield from pipeline.passes(sc, integ, settings)
        return
    for prog, buf in job.job.passes():
        job.buffer = buf
        yield prog


def finish(sc, settings, job, prog) -> np.ndarray:
    """The denoised image (H x W x 3) of the finished passes; keeps the denoised buffer for restyles."""
    if isinstance(job, _Expectation):
        image, buf = job.job.finish(job.buffer)
        if settings.record_buffer:
            from . import restyle
            restyle.keep(buf)
        return image
    from ..denoise.image import denoise
    return denoise(sc, np.asarray(prog.image, dtype=np.float32), prog.spp_done, settings.seed,
                   settings.denoise_quality)


__all__ = ["prepare", "passes", "finish"]
