"""A style of one child previews as it renders: at the defaults (denoise auto) its render is
finished by the image denoiser (`--denoise image --denoise-footprint film`), and the page's full
restyle, denoised as that render is, equals `styletrace render` of the page's command line; a
style of several children (cel) denoises the expectation."""
import numpy as np
import pytest

from styletrace.lookdev.restyle import restyle
from styletrace.preview.jobs import page_job

from .conftest import finished, run_command

pytest.importorskip("pyoidn", reason="the 'denoise' extra (pyoidn) is not installed")

SIZE = 32


@pytest.mark.parametrize("style,params,method", [
    ("contrast", {"c": "1.6", "pivot": "auto", "exposure": "auto"}, "image"),
    ("identity", {}, "image"),
    ("cel", {"bands": "3", "thresholds": "auto", "levels": "auto"}, "expectation"),
])
def test_the_full_restyle_is_the_command_lines_render(style, params, method, monkeypatch,
                                                      tmp_path):
    monkeypatch.delenv("STYLETRACE_DENOISE", raising=False)  # the default: auto
    restyled = []  # each frame's restyle, as the page would show it, made as it came

    def on_image(frame):
        image = restyle(frame.buffer, style=style, **params)
        restyled.append(frame.denoiser(image) if frame.denoiser is not None else image)

    s = finished(page_job("cornell-box", style=style, width=SIZE, height=SIZE), on_image)
    st = s.state()
    print(style, st["method"], st["note"], [(f.kind, f.label) for f in s.frames])
    assert st["method"] == method
    assert (st["children"] == 1) == (method == "image")
    kinds = [f.kind for f in s.frames]
    assert kinds[0] == "draft" and kinds[-1] == "final" and "preview" in kinds
    if method == "image":  # every full-size image is the image denoiser's
        assert all(f.denoiser is not None for f in s.frames[1:])
    assert all(np.isfinite(x).all() for x in restyled) and len(restyled) == len(kinds)
    image, spp, children = s.restyle(style, None, params)
    command = s.command(style, None, params)
    print(command)
    assert f"--denoise {method}" in command
    assert ("--denoise-footprint film" in command) == (method == "image")
    np.testing.assert_allclose(image, run_command(command, tmp_path), rtol=1e-4, atol=1e-5)
    # the restyle the page shows once the session is done is the last frame's, restyled
    np.testing.assert_array_equal(image, restyled[-1])
