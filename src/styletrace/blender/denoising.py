"""F12 with Denoise on: the render settings' `denoise` ("expectation" or "image") through styletrace's denoisers.

- expectation (`denoise.expectation.Job`): the passes record the expectation buffer; after the last pass (or a
  cancel) the expectation is denoised and the style applied. With Record buffer on, the buffer kept for restyling
  is the denoised one, so a style change restyles to what a denoised F12 with the new value gives.
- image (`denoise.image.finish`): the passes as usual, then OIDN on the image. Record buffer is refused with it:
  restyles of a noisy buffer would not be the denoised image F12 showed.
Both are the command line's (`styletrace render FILE.xml --denoise ... --pass-spp N`: the same image for the same
seed and pass split). Without the `denoise` extra (pyoidn), F12 refuses in one line naming it.
"""
from __future__ import annotations

from typing import Iterator

import numpy as np

from .. import api
from ..denoise.expectation import Job
from ..errors import UsageError
from . import pipeline


def method(sc, integ, settings) -> tuple[str, str]:
    """(the method F12 uses: expectation, image or off; the one-line note where auto could not denoise)."""
    from ..denoise.default import method_for
    size = sc.sensors()[0].film().crop_size()
    return method_for(sc, integ, settings.denoise, samples=int(size[0]) * int(size[1]) * int(settings.spp))


def prepare(sc, integ, settings, used: str):
    """None without denoising (`used`: `method`'s choice); else what `passes` and `finish` need, after every
    refusal (one line each)."""
    if used == "off":
        return None
    from ..denoise import oidn
    oidn.require()
    oidn.check_quality(settings.denoise_quality)
    if used == "image":
        if settings.record_buffer:
            raise UsageError("Record buffer with Denoise 'image': restyles of the noisy buffer would not be the "
                             "denoised image; use Denoise 'expectation' (its buffer keeps the denoised expectation)")
        return used
    return Job(sc, integ, settings.spp, settings.seed, settings.denoise_quality, label="<blender>",
               pass_spp=settings.pass_spp)


def passes(job, sc, integ, settings) -> Iterator[api.Progress]:
    """F12's passes: the expectation job's (recording its buffer), or the ordinary ones for image denoising."""
    if not isinstance(job, Job):
        return pipeline.passes(sc, integ, settings)
    return (prog for prog, _ in job.passes())


def finish(sc, settings, job, prog) -> np.ndarray:
    """The denoised image (H x W x 3) of the finished passes; keeps the denoised buffer for restyles."""
    if isinstance(job, Job):
        image, buf = job.finish()
        if settings.record_buffer:
            from . import restyle
            restyle.keep(buf)
        return image
    from ..denoise.image import finish as denoised
    return denoised(sc, prog, settings.seed, settings.denoise_quality)[0]


__all__ = ["method", "prepare", "passes", "finish"]
