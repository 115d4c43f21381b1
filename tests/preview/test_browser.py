"""The preview page in a real browser: Chromium (Debian's package) driven by Playwright.

It loads the page, moves a parameter's slider, and requires the image to change within CHANGE_S
seconds (a functional timeout for a loaded 2-core machine, not a speed claim: speed is in
BENCHMARKS.md); then it clicks "save EXR" and checks the file is exactly what `styletrace.restyle`
returns for the page's settings. A drag with the mouse sends quick restyles (one point per pixel)
and, at its release, a full one, whose image the page shows. At 512 x 512 the page times each
dragged value from its input event to the frame that shows it, and shows that time.
"""
import base64
import contextlib
import os
import re

import numpy as np
import pytest

from styletrace.gate import mi
from styletrace.images import srgb8
from styletrace.lookdev.restyle import restyle
from styletrace.preview.jobs import page_job

from .conftest import finished, served, wait_until

CHROMIUM = "/usr/bin/chromium"
CHANGE_S = 10
#: the page's first image: the canvas holds a restyle
DRAWN = "document.getElementById('image').dataset.stamp !== undefined"


@pytest.fixture(scope="module")
def browser():
    sync_api = pytest.importorskip(
        "playwright.sync_api", reason="pip extra 'preview' (bash dev.sh test installs it)"
    )
    assert os.path.exists(CHROMIUM), (
        "Chromium is missing: apt-get install chromium (bash dev.sh test installs it)"
    )
    with sync_api.sync_playwright() as pw:
        b = pw.chromium.launch(executable_path=CHROMIUM, headless=True, args=["--no-sandbox"])
        yield b
        b.close()


@contextlib.contextmanager
def opened(browser, url):
    pg = browser.new_page(accept_downloads=True)
    try:
        pg.goto(url)
        pg.wait_for_function(DRAWN, timeout=CHANGE_S * 1000)
        yield pg
    finally:
        pg.close()


@pytest.fixture
def page(browser, server):
    with opened(browser, server) as pg:
        yield pg


def canvas(page) -> np.ndarray:
    """The pixels the page's canvas holds, H x W x 4 (sRGB 8-bit RGBA)."""
    w, h, data = page.evaluate("""() => { const c = document.getElementById('image');
        const d = c.getContext('2d').getImageData(0, 0, c.width, c.height).data;
        let s = '';
        for (let i = 0; i < d.length; i += 8192)
          s += String.fromCharCode.apply(null, d.subarray(i, i + 8192));
        return [c.width, c.height, btoa(s)]; }""")
    return np.frombuffer(base64.b64decode(data), dtype=np.uint8).reshape(h, w, 4)


def assert_shows(page, image):
    """The canvas holds `image` (linear) in sRGB 8-bit, within the one level `server.rgba8`
    allows."""
    got = canvas(page)
    assert got.shape == image.shape[:2] + (4,) and (got[..., 3] == 255).all()
    assert np.abs(got[..., :3].astype(int) - srgb8(image)).max() <= 1


def pick(page, style):
    page.select_option("#style", style)
    page.wait_for_function(
        f"document.getElementById('command').value.includes('--style {style}')",
        timeout=CHANGE_S * 1000,
    )


def test_moving_a_slider_restyles_and_save_writes_the_restyle(page, session, tmp_path):
    pick(page, "contrast")
    before = canvas(page)
    slider = page.locator('[data-param="c"]')
    slider.fill("3")  # sets the range input's value and fires its input event
    value = slider.input_value()
    page.wait_for_function("(v) => document.getElementById('command').value.includes(v)",
                           arg=f"--set c={value}", timeout=CHANGE_S * 1000)
    assert not np.array_equal(canvas(page), before)

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
    # at rest the page shows that restyle
    page.wait_for_function("document.getElementById('image').dataset.quick === 'false'",
                           timeout=CHANGE_S * 1000)
    assert_shows(page, want)


def drag(page, session, param, fractions):
    """Drag the slider of `param` with the mouse through `fractions` of its width, each new value
    waited for as a quick restyle of the session (a functional timeout, not a speed claim), then
    release it."""
    box = page.locator(f'[data-param="{param}"]').bounding_box()
    y = box["y"] + box["height"] / 2
    quick = session.counts["quick"]
    page.mouse.move(box["x"] + fractions[0] * box["width"], y)
    page.mouse.down()
    for f in fractions[1:]:
        page.mouse.move(box["x"] + f * box["width"], y)
        wait_until(lambda: session.counts["quick"] > quick, CHANGE_S, "a quick restyle")
        quick = session.counts["quick"]
    page.mouse.up()


def test_dragging_a_slider_restyles_quickly_then_rests_on_the_whole_buffer(page, session):
    """A real drag of contrast's c with the mouse: each new value (an `input` event) is sent as a
    quick restyle (one point per pixel), the release (`change`) as a full one; the image shown
    after the drag is the full restyle of the session's buffer."""
    pick(page, "contrast")
    # every image the page draws: whether it was a quick restyle
    page.evaluate("""() => { const c = document.getElementById('image'); window.drawn = [];
        new MutationObserver(() => window.drawn.push(c.dataset.quick))
          .observe(c, { attributes: true, attributeFilter: ['data-stamp'] }); }""")
    full = session.counts["full"]
    drag(page, session, "c", (0.2, 0.3, 0.4, 0.5, 0.6, 0.7))
    wait_until(lambda: session.counts["full"] > full, CHANGE_S, "the restyle at rest")
    page.wait_for_function("document.getElementById('image').dataset.quick === 'false'",
                           timeout=CHANGE_S * 1000)
    sent = page.evaluate("() => request().params")
    assert 0.5 < float(sent["c"]) < 1.5  # the slider ran from 0 to 2: released at 0.7 of it
    drawn = page.evaluate("() => window.drawn")
    assert "true" in drawn and drawn[-1] == "false", drawn
    assert_shows(page, restyle(session.buffer, style="contrast", **sent))
    assert f"--set c={sent['c']}" in page.input_value("#command")


def test_the_page_times_a_dragged_value_from_its_input_to_the_screen(browser):
    """At 512 x 512 (a budget of one path per pixel, so that the session ends at once): a drag's
    values are timed by the page from the input event that asked for each to the frame that
    paints it, and shown. Checked: each time starts at a real input event's timeStamp, ends
    after the image was drawn, and holds the server's time for its request; printed, not judged
    (the speed is BENCHMARKS.md's, `benchmarks/preview_latency.py`)."""
    s = finished(page_job("cornell-box", style="contrast", samples=1, width=512, height=512))
    try:
        with served(s) as url, opened(browser, url) as pg:
            assert pg.evaluate("() => [document.getElementById('image').width, "
                               "document.getElementById('image').height]") == [512, 512]
            pg.evaluate("""() => { window.inputs = [];
                document.querySelector('[data-param="c"]').addEventListener(
                  'input', (e) => window.inputs.push(e.timeStamp)); }""")
            drag(pg, s, "c", (0.2, 0.25, 0.3, 0.35, 0.4, 0.45, 0.5, 0.55, 0.6))
            pg.wait_for_function("window.latencies.filter((x) => x.quick).length >= 3",
                                 timeout=CHANGE_S * 1000)
            pg.wait_for_function("document.getElementById('image').dataset.quick === 'false'",
                                 timeout=CHANGE_S * 1000)
            # one snapshot: the page pushes a measurement and shows it in the same callback
            lat, inputs, status, summary = pg.evaluate(
                "() => [window.latencies, window.inputs, "
                "document.getElementById('status').textContent, "
                "document.getElementById('latency').textContent]")
    finally:
        s.stop()
    print("\n".join(f"{'quick' if x['quick'] else 'full '} shown {x['ms']:.1f} ms after the "
                    f"input (server {x['server_ms']:.1f} ms, restyle {x['restyle_ms']:.1f} ms)"
                    for x in lat))
    print(status, "|", summary)
    quick = [x for x in lat if x["quick"]]
    assert len(quick) >= 3 and all(x["bytes"] == 512 * 512 * 4 for x in lat)
    for x in lat:
        assert x["input"] in inputs or not x["quick"]  # a full one: the release's change event
        assert x["input"] <= x["sent"] <= x["answered"] <= x["received"] <= x["drawn"] \
            <= x["shown"]
        assert x["ms"] == pytest.approx(x["shown"] - x["input"])
        assert x["ms"] >= x["server_ms"] > 0  # the server's time is within the page's
    # the page shows them: the median and the largest of all, and the newest with its server's
    ms = sorted(x["ms"] for x in lat)
    shown = re.fullmatch(r"input to screen: median (\d+) ms, largest (\d+) ms over (\d+) images",
                         summary)
    assert shown, summary
    median, largest, count = (int(v) for v in shown.groups())
    assert count == len(ms) and abs(median - ms[len(ms) // 2]) <= 0.5 + 1e-9 \
        and abs(largest - ms[-1]) <= 0.5 + 1e-9, (summary, ms)
    assert "ms after the input (server" in status or "; server" in status, status
