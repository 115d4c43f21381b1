"""The denoised-expectation job's preview for a viewport (`ExpectationJob.preview`).

- A preview denoises with the quality asked for and evaluates g where asked: at one point per pixel
  its buffer holds one point per pixel and restyles to its image (up to float rounding, as
  test_restyle.py); at k = 0 at the camera samples, on a copy of the recorded buffer; another OIDN
  quality gives another image (so the quality reaches OIDN).
- Previews leave `finish` as it was: after previews at k = 0 and k = 1 between the passes (what a
  preview keeps for the next and for `finish`: the guides, each pass's own albedo and emission),
  `finish` gives the image and buffer of a job with no preview, bit for bit, and the recorded
  buffer holds no D.
- A bad k or quality: one line.
"""
import numpy as np
import pytest

import styletrace
from styletrace.denoise import expectation as X
from styletrace.errors import UsageError
from styletrace.frontends import api
from styletrace.pipeline.denoising import Denoising
from styletrace.pipeline.passes import PassSplit, Shot

RES = 16


def job():
    scene = api.load_scene("cornell-box", RES, RES)
    # with an uncertainty, so that the spread a finish keeps is compared too
    return X.ExpectationJob(Shot(scene, api.make_integrator(style="cel", inner=2), 2, 4),
                            Denoising("expectation", coverage=4, uncertainty=0.3),
                            split=PassSplit(pass_spp=1))


@pytest.fixture(scope="module")
def finished():
    """(job, previews after each pass, finish's result) and a job finished without previews."""
    j, previews = job(), []
    for _ in j.passes():
        previews.append({(k, q): j.preview(k, q) for k, q in ((0, "fast"), (1, "balanced"),
                                                              (1, "fast"))})
    plain = job()
    for _ in plain.passes():
        pass
    return j, previews, j.finish(), plain.finish()


def test_finish_after_previews_is_finish_without(finished):
    j, _, (image, cover), (plain_image, plain_cover) = finished
    assert len(j.buffer.header["passes"]) == 2
    np.testing.assert_array_equal(image, plain_image)
    for k in ("mean", "denoise_spread", "p", "slot"):
        np.testing.assert_array_equal(cover.arrays[k], plain_cover.arrays[k])
    assert X.DENOISED not in j.buffer.arrays and cover.source is j.buffer


def test_a_preview_is_the_denoised_render_at_its_k_and_quality(finished):
    j, previews, (image, _), _ = finished
    last = previews[-1]
    im1, b1 = last[1, "fast"]
    assert b1.camera_samples == RES * RES and b1.header["denoise"]["coverage"] == 1
    assert b1.header["denoise"]["quality"] == "fast" and b1.source is j.buffer
    assert np.abs(styletrace.restyle(b1) - im1).max() <= 1e-5
    im0, b0 = last[0, "fast"]
    assert X.DENOISED in b0.arrays and b0.source is j.buffer
    assert b0.camera_samples == j.buffer.camera_samples
    assert np.abs(styletrace.restyle(b0) - im0).max() <= 1e-5
    # the quality reaches OIDN, and one point per pixel is not sixteen
    assert np.abs(last[1, "balanced"][0] - im1).max() > 1e-4
    assert np.abs(image - im1).max() > 1e-4
    # the first pass's preview saw one camera sample per pixel, the second's two
    assert previews[0][0, "fast"][1].camera_samples == RES * RES


def test_bad_values_are_refused():
    j = job()
    with pytest.raises(UsageError, match="nothing to denoise"):
        j.preview()
    with pytest.raises(UsageError, match="bad value 2 for coverage"):
        j.preview(2)
    with pytest.raises(UsageError, match="bad value 'best' for denoise quality"):
        j.preview(1, "best")
