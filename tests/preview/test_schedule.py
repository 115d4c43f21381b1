"""The preview's schedule (`progressive.schedule`, issue 36): a draft, quick denoised previews
after the passes `denoise_now` picks, then the command line's render; each image no noisier than
the one before; drags restyled at one point per pixel, without a pass and without waiting for
one; a style of one child previewed as it renders (the image denoiser)."""
import threading

import numpy as np
import pytest

import styletrace
from styletrace.lookdev.restyle import restyle
from styletrace.lookdev.slider import quick_restyle
from styletrace.measures import srgb
from styletrace.preview.jobs import page_job
from styletrace.preview.session import Session

from .conftest import JOIN_S, finished, run_command

pytest.importorskip("pyoidn", reason="the 'denoise' extra (pyoidn) is not installed")

SIZE = 64


def denoised_session(seed=0, on_image=None):
    """A finished session on the Cornell box at SIZE x SIZE, its expectation denoised, at the
    scene's 16 samples (4 passes of one camera sample of 4 children)."""
    return finished(page_job("cornell-box", width=SIZE, height=SIZE, seed=seed,
                             denoise="expectation"), on_image)


def test_the_schedule_ends_at_the_command_lines_render(tmp_path):
    s = denoised_session()
    st = s.state()
    assert (st["samples"], st["spp"], st["children"]) == (16, 4, 4)  # budget.CHILDREN
    kinds = [x.kind for x in s.frames]
    labels = [x.label for x in s.frames]
    print("images:", [(x.label, f"{x.seconds:.2f} s") for x in s.frames],
          "denoise:", s.stats["denoise_s"])
    # the draft, a preview after the first pass, previews where `denoise_now` says, the finisher
    assert kinds[0] == "draft" and kinds[-1] == "final"
    assert set(kinds[1:-1]) == {"preview"}
    assert labels[0] == f"draft, denoised ({SIZE}x{SIZE}, 1 spp)"  # at most DRAFT_PIXELS
    assert labels[1] == "pass 1/4, 1 spp, denoised (preview)"
    assert labels[-1] == "pass 4/4, 4 spp, denoised"
    assert [x.version for x in s.frames] == list(range(1, len(kinds) + 1))
    assert [x.spp for x in s.frames] == sorted(x.spp for x in s.frames)
    assert [x.children for x in s.frames] == [4] * len(kinds)
    assert len(s.stats["pass_s"]) == 4 and len(s.stats["denoise_s"]) == len(kinds) - 1
    # the last image, restyled, is the page's command line run as it reads
    params = {"bands": "3", "thresholds": "auto", "levels": "auto"}  # as the page sends them
    image, spp, inner = s.restyle("cel", None, params)
    command = s.command("cel", None, params)
    assert command == ("styletrace render cornell-box --style cel --inner 4 --spp 4 --seed 0 "
                       "--pass-spp 1 --denoise expectation --width 64 --height 64 "
                       "--set bands=3 --set thresholds=auto --set levels=auto -o render.png")
    want = run_command(command, tmp_path)
    # equal to float rounding, not in every bit: the restyle passes θ as kernel inputs, the render
    # as literals (docs/design/slider_restyles.md)
    np.testing.assert_allclose(image, want, rtol=1e-5, atol=1e-6)
    assert (spp, inner) == (4, 4)


def test_each_image_is_no_noisier_than_the_one_before():
    """Two sessions that differ only in the seed: along the images both showed (the draft, the
    previews after the passes `denoise_now` picked, the last image), each restyled with cel as the
    page shows it, the noise between the seeds never grows. The noise of an image: the mean
    squared difference of the two seeds' images in sRGB; a later one may exceed an earlier one by
    at most 3 standard errors of the difference, from 8 x 8 blocks (denoised pixels are correlated,
    so single pixels would understate it)."""
    images = []
    for seed in (1, 2):
        shown = {}
        denoised_session(seed, lambda x: shown.__setitem__(x.label, restyle(x.buffer,
                                                                            style="cel")))
        images.append(shown)
    a, b = images
    labels = [label for label in a if label in b]
    print("images:", list(a), list(b))
    assert len(labels) >= 3 and labels[0].startswith("draft") and labels[-1].startswith("pass 4/4")
    d2 = [(srgb(a[k]) - srgb(b[k])) ** 2 for k in labels]
    for k in range(1, len(labels)):
        diff = blocks((d2[k] - d2[k - 1]).mean(-1), 8).ravel()
        se = diff.std(ddof=1) / np.sqrt(diff.size)
        z = diff.mean() / se if se > 0 else 0.0  # the same image twice: no difference at all
        print(f"{labels[k - 1]} -> {labels[k]}: noise {d2[k - 1].mean():.3e} -> "
              f"{d2[k].mean():.3e} (z {z:.2f})")
        assert diff.mean() <= 3 * se


def blocks(img: np.ndarray, b: int) -> np.ndarray:
    """The means of b x b pixel blocks of an H x W image."""
    h, w = img.shape[0] - img.shape[0] % b, img.shape[1] - img.shape[1] % b
    return img[:h, :w].reshape(h // b, b, w // b, b).mean(axis=(1, 3))


def test_a_drag_restyles_one_point_per_pixel_then_rests_on_the_whole_buffer():
    s = denoised_session()
    final, shown, passes = s.buffer, list(s.frames), len(s.stats["pass_s"])
    counts = dict(s.counts)
    values = ("0.1,0.3,0.9", "0.1,0.35,0.9", "0.1,0.4,0.9", "0.1,0.45,0.9")
    quick = []
    for levels in values:
        r = s.styled("cel", None, {"levels": levels}, quick=True, wait=False)
        assert r.quick and not r.busy and r.shown is shown[-1]
        np.testing.assert_array_equal(r.image, quick_restyle(final, style="cel", levels=levels))
        quick.append(r.image)
    assert s.counts["quick"] == counts["quick"] + len(values)
    # no new pass, no new image: the drag restyles the last image's buffer
    assert len(s.stats["pass_s"]) == passes and s.frames == shown and s.buffer is final
    # at rest: the whole buffer, exactly `restyle.restyle` of it
    rest = s.styled("cel", None, {"levels": values[-1]}, wait=False)
    want = restyle(final, style="cel", levels=values[-1])
    assert not rest.quick and not rest.busy
    np.testing.assert_array_equal(rest.image, want)
    assert not np.array_equal(rest.image, quick[-1])  # one point per pixel is not the whole look
    # the same request again is answered with that restyle, with no new one
    again = s.styled("cel", None, {"levels": values[-1]}, quick=True, wait=False)
    assert again.stamp == rest.stamp and s.counts["kept"] == counts["kept"] + 1


def test_a_restyle_never_waits_for_a_pass():
    """A request made while a pass holds the session's lock is answered at once, busy; the render
    thread restyles its style after the pass, and answers its later requests without the lock."""
    answers = []

    def during_the_draft(x):  # called under the lock, as a pass holds it
        if x.kind == "draft":
            t = threading.Thread(target=lambda: answers.append(
                s.styled("contrast", None, {"c": "2"}, quick=True, wait=False)))
            t.start()
            t.join(60)  # a request that waited for the lock would still be waiting here

    s = Session(page_job("cornell-box", width=SIZE, height=SIZE, denoise="expectation"),
                on_image=during_the_draft)
    s.start()
    s.join(JOIN_S)
    assert s.done and s.error is None and len(answers) == 1
    busy = answers[0]
    assert busy.busy and busy.image is None and busy.shown.kind == "draft"
    # the render thread restyled it after its pass, and again on every image since: the last
    # image's is there without a restyle, even while the lock is held
    want = quick_restyle(s.buffer, style="contrast", c="2")
    with s.schedule.turns:
        kept = s.styled("contrast", None, {"c": "2"}, quick=True, wait=False)
        other = s.styled("contrast", None, {"c": "3"}, quick=True, wait=False)
    assert not kept.busy and kept.shown is s.frames[-1]
    np.testing.assert_array_equal(kept.image, want)
    # another value of the same style, busy: the render thread's newest restyle of that style
    assert other.busy and other.stamp == s.state()["restyled"]
    np.testing.assert_array_equal(other.image, want)
    assert s.counts["busy"] == 2
    # a bad value is refused on the host, busy or not
    with s.schedule.turns, pytest.raises(styletrace.StyletraceError, match="bad value"):
        s.styled("contrast", None, {"c": "-1"}, quick=True, wait=False)
