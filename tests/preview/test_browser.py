"""The preview page in a real browser: Chromium (Debian's package) driven by Playwright.

It loads the page, moves a parameter's slider, and requires the image to change within CHANGE_S
seconds (a functional timeout for a loaded 2-core machine, not a speed claim: speed is in
BENCHMARKS.md); then it clicks "save EXR" and checks the file is exactly what `styletrace.restyle`
returns for the page's settings.
"""
import os

import numpy as np
import pytest

from styletrace.gate import mi
from styletrace.lookdev.restyle import restyle

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
