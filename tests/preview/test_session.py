"""The preview session: its draft (one camera sample of the render's children at the draft's size)
and its films, each restyle equal to `styletrace render` of the page's command line."""
import numpy as np

from styletrace.lookdev.restyle import restyle
from styletrace.preview.jobs import page_job
from styletrace.preview.session import Session
from styletrace.progressive.rules import draft_size

from .conftest import JOIN_S, finished, run_command


def test_the_draft_is_one_camera_sample_of_the_renders_children_at_the_draft_size(tmp_path):
    """A film above the draft's pixels is drafted smaller (`rules.draft_size`), with the render's
    children; restyled, the draft is the page's draft command line run. The session is stopped
    from its draft's callback, so the draft stays the image restyles read."""
    size = (200, 150)
    s = Session(page_job("cornell-box", inner=4, spp=2, width=size[0], height=size[1]),
                on_image=lambda frame: frame.kind == "draft" and s.schedule.stop())
    assert s.restyle("cel", None, {}) == (None, 0, 0)  # nothing rendered yet
    s.start()
    s.join(JOIN_S)
    assert s.done and s.error is None
    assert [f.kind for f in s.frames] == ["draft"] and s.buffer is None
    st = s.state()
    assert st["draft"] and st["kind"] == "draft" and (st["width"], st["height"]) == size
    assert (st["samples"], st["spp"], st["children"]) == (8, 2, 4)
    img, spp, children = s.restyle("cel", None, {})
    dw, dh = draft_size(*size)
    assert (dw, dh) == (160, 120) and img.shape == (dh, dw, 3)
    assert (spp, children) == (1, 4)
    command = s.command("cel", None, {}, draft=True)
    assert "--inner 4 --spp 1 " in command and "--width 160 --height 120" in command
    print(command)
    np.testing.assert_allclose(img, run_command(command, tmp_path), rtol=1e-5, atol=1e-6)
    # the page's own command line names the render the session would end with
    assert "--inner 4 --spp 2 " in s.command("cel", None, {})


def test_a_film_with_a_gaussian_filter(tmp_path):
    """The session records and restyles a film with Mitsuba's default filter (no rfilter: a
    gaussian): the restyle is the render of the page's command line (1 spp per pass)."""
    from helpers.filtered_scene import GAUSSIAN_SCENE
    scene = tmp_path / "g.xml"
    scene.write_text(GAUSSIAN_SCENE)
    s = finished(page_job(str(scene), style="sepia", inner=2, spp=2))
    assert s.buffer.filtered
    img, spp, children = s.restyle("sepia", None, {})
    command = s.command("sepia", None, {})
    s.stop()
    assert (spp, children) == (2, 2) and s.state()["bytes_per_camera_sample"] == 74
    want = run_command(command, tmp_path)
    np.testing.assert_allclose(img, want, rtol=1e-5, atol=1e-6)
    np.testing.assert_array_equal(img, restyle(s.buffer, style="sepia"))
