"""The preview session: a draft (1 spp, n = 1) is shown before the first full pass."""
import numpy as np

import styletrace
from styletrace.lookdev.restyle import restyle

from .conftest import wait_until


def test_the_draft_is_a_one_child_render_served_until_the_first_full_pass(monkeypatch):
    from styletrace.preview import session as module
    # the render thread waits for the draft to be shown
    monkeypatch.setattr(module, "DRAFT_GRACE_S", 120.0)
    from styletrace.denoise.draft import (  # with the denoise extra the draft is denoised
        QUALITY,
        available,
    )
    # the draft styles D at its camera samples (coverage 0: it must stay the buffer the page
    # restyles); rendered before the session starts: the page's Dr.Jit work runs under the session's
    # lock, a render of the test's own beside the session's render thread would not (a CI run once
    # failed there with an empty-array gather)
    extra = (
        {"denoise": "expectation", "denoise_quality": QUALITY, "coverage": 0} if available() else {}
    )
    want = styletrace.render(
        "cornell-box",
        style="cel",
        spp=1,
        inner=module.DRAFT_INNER,
        seed=0,
        width=24,
        height=20,
        **extra,
    )
    s = module.Session("cornell-box", inner=2, spp=2, width=24, height=20)
    assert s.restyle("cel", None, {}) == (None, 0, 0)  # nothing rendered yet
    s.start()
    wait_until(lambda: s.draft is not None, 120, "the draft")
    assert s.buffer is None and s.state()["draft"]
    img, spp, inner = s.restyle("cel", None, {})
    assert (spp, inner) == (1, module.DRAFT_INNER)
    np.testing.assert_allclose(img, want, rtol=0, atol=1e-5)
    assert "--inner 1 --spp 1" in s.command("cel", None, {}, spp, inner)
    wait_until(lambda: s.done or s.error, 120, "the background render")
    assert s.error is None
    img, spp, inner = s.restyle("cel", None, {})
    assert (spp, inner) == (2, 2) and not s.state()["draft"]
    np.testing.assert_array_equal(img, restyle(s.buffer, style="cel"))
    s.stop()


def test_a_film_with_a_gaussian_filter(tmp_path):
    """The session records and restyles a film with Mitsuba's default filter (no rfilter: a
    gaussian): the restyle is the render of the page's command line (1 spp per pass)."""
    from helpers.filtered_scene import GAUSSIAN_SCENE

    from styletrace.preview import session as module
    scene = tmp_path / "g.xml"
    scene.write_text(GAUSSIAN_SCENE)
    want = styletrace.render(str(scene), style="sepia", spp=2, inner=2, seed=0, pass_spp=1)
    s = module.Session(str(scene), inner=2, spp=2).start()
    wait_until(lambda: s.done or s.error, 120, "the background render")
    assert s.error is None and s.buffer.filtered
    img, spp, inner = s.restyle("sepia", None, {})
    s.stop()
    assert (spp, inner) == (2, 2) and s.state()["bytes_per_camera_sample"] == 74
    np.testing.assert_allclose(img, want, rtol=1e-5, atol=1e-6)
