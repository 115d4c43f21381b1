"""The preview page in a real browser: Chromium (Debian's package) driven by Playwright.

It loads the page, moves a parameter's slider, and requires the image to change within CHANGE_S
seconds (a functional timeout for a loaded 2-core machine, not a speed claim: speed is in
BENCHMARKS.md); then it clicks "save EXR" and checks the file is exactly what `styletrace.restyle`
returns for the page's settings. A drag with the mouse sends quick restyles (one point per pixel)
and, at its release, a full one, whose image the page shows.
"""
import base64
import os

import numpy as np
import pytest

from styletrace.gate import mi
from styletrace.lookdev.restyle import restyle

from .conftest import wait_until

CHROMIUM = "/usr/bin/chromium"
CHANGE_S = 10


@pytest.fixture(scope="module")
def page(server):
    sync_api = pytest.importorskip(
        "playwright.sync_api", reason="pip extra 'preview' (bash dev.sh test installs it)"
    )
    assert os.path.exists(CHROMIUM), (
        "Chromium is missing: apt-get install chromium (bash dev.sh test installs it)"
    )
    with sync_api.sync_playwright() as pw:
        browser = pw.chromium.launch(executable_path=CHROMIUM, headless=True, args=["--no-sandbox"])
        pg = browser.new_page(accept_downloads=True)
        pg.goto(server)
        yield pg
        browser.close()


def image_src(page):
    return page.get_attribute("#image", "src") or ""


def test_moving_a_slider_restyles_and_save_writes_the_restyle(page, session, tmp_path):
    page.wait_for_function("document.getElementById('image').src.startsWith('data:image/png')",
                           timeout=CHANGE_S * 1000)
    page.select_option("#style", "contrast")
    page.wait_for_function(
        "document.querySelector('[data-param=\"c\"]') !== null", timeout=CHANGE_S * 1000
    )
    page.wait_for_function("document.getElementById('command').value.includes('--style contrast')",
                           timeout=CHANGE_S * 1000)
    before = image_src(page)
    slider = page.locator('[data-param="c"]')
    slider.fill("3")  # sets the range input's value and fires its input event
    value = slider.input_value()
    page.wait_for_function(
        "(before) => document.getElementById('image').src !== before",
        arg=before,
        timeout=CHANGE_S * 1000,
    )
    assert f"--set c={value}" in page.input_value("#command")

    with page.expect_download() as info:
        page.click("#save-exr")
    path = str(tmp_path / "saved.exr")
    info.value.save_as(path)
    # pivot and exposure are scene-relative (`auto`, styles.contrast): their sliders stand at a
    # placeholder position and the page sends "auto", which the saved image resolves on the scene
    sent = page.evaluate("() => request().params")
    assert sent == {"c": value, "pivot": "auto", "exposure": "auto"}
    assert "--set pivot=auto" in page.input_value("#command")
    want = restyle(session.buffer, style="contrast", **sent)
    np.testing.assert_array_equal(np.array(mi.Bitmap(path), dtype=np.float32), want)


def test_dragging_a_slider_restyles_quickly_then_rests_on_the_whole_buffer(page, server, session):
    """A real drag of contrast's c with the mouse: each new value (an `input` event) is sent as a
    quick restyle (one point per pixel), the release (`change`) as a full one; the image shown
    after the drag is the full restyle of the session's buffer."""
    from styletrace.preview.server import encode_image_file
    page.goto(server)
    page.wait_for_function("document.getElementById('image').src.startsWith('data:image/png')",
                           timeout=CHANGE_S * 1000)
    page.select_option("#style", "contrast")
    page.wait_for_function("document.getElementById('command').value.includes('--style contrast')",
                           timeout=CHANGE_S * 1000)
    # every image the page shows: whether it was a quick restyle
    page.evaluate("""() => { const img = document.getElementById('image'); window.shown = [];
        new MutationObserver(() => window.shown.push(img.dataset.quick))
          .observe(img, { attributes: true, attributeFilter: ['src'] }); }""")
    box = page.locator('[data-param="c"]').bounding_box()
    y = box["y"] + box["height"] / 2
    quick, full = session.counts["quick"], session.counts["full"]
    page.mouse.move(box["x"] + 0.2 * box["width"], y)
    page.mouse.down()
    for f in (0.3, 0.4, 0.5, 0.6, 0.7):
        page.mouse.move(box["x"] + f * box["width"], y)
        # each new value is sent as a quick restyle (a functional timeout, not a speed claim)
        wait_until(lambda: session.counts["quick"] > quick, CHANGE_S, "a quick restyle")
        quick = session.counts["quick"]
    page.mouse.up()
    wait_until(lambda: session.counts["full"] > full, CHANGE_S, "the restyle at rest")
    page.wait_for_function("document.getElementById('image').dataset.quick === 'false'",
                           timeout=CHANGE_S * 1000)
    sent = page.evaluate("() => request().params")
    assert 0.5 < float(sent["c"]) < 1.5  # the slider ran from 0 to 2: released at 0.7 of it
    shown = page.evaluate("() => window.shown")
    assert "true" in shown and shown[-1] == "false", shown
    want = restyle(session.buffer, style="contrast", **sent)
    png = "data:image/png;base64," + base64.b64encode(encode_image_file(want, "png")).decode()
    assert image_src(page) == png
    assert f"--set c={sent['c']}" in page.input_value("#command")
