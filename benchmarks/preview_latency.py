"""The preview page's slider: from a dragged value's input event to the image the browser shows.

    .venv/bin/python benchmarks/preview_latency.py [--runs 3] [--moves 30] [--hz 60] [--no-write]

A `styletrace preview` of the built-in `lines` scene at 512 x 512 at the defaults (cel, Samples
16, denoise auto), its schedule run to its end, served by uvicorn on 127.0.0.1; headless Chromium
(Debian's, driven by Playwright) opens the page, picks `contrast` and drags its `c` slider with the
mouse: --moves positions at --hz (a mouse's event rate), then the release. The page's own
measurements (`window.latencies`, docs/preview.md) are read: for each image shown for an input,
the time from that input event (`event.timeStamp`) to the frame that paints it, with the server's
time for its request (restyle and encoding of the answer) and the restyle's own. One untimed drag
first (the contrast kernels compiled), then --runs drags, each in a fresh page. Values that come
while a request is out wait, the newest replacing the others (never shown: superseded), and the
oldest waiting input event times the next image shown. Writes the BENCHMARKS.md section
"preview_latency"; the goal (issue 44) is a dragged value on screen within 50 ms at 512 x 512.
"""
from __future__ import annotations

import argparse
import contextlib
import os
import statistics
import threading
import time

from _report import machine_description, write_section

import styletrace

CHROMIUM = "/usr/bin/chromium"
GOAL_MS = 50.0
SCENE, SIZE = "lines", 512


@contextlib.contextmanager
def served(session):
    """The session's page served on a free port of 127.0.0.1 in a thread; yields its URL."""
    import uvicorn

    from styletrace.preview.server import make_app
    srv = uvicorn.Server(uvicorn.Config(make_app(session), host="127.0.0.1", port=0,
                                        log_level="warning"))
    thread = threading.Thread(target=srv.run, daemon=True)
    thread.start()
    while not srv.started:
        time.sleep(0.01)
    try:
        yield f"http://127.0.0.1:{srv.servers[0].sockets[0].getsockname()[1]}/"
    finally:
        srv.should_exit = True
        thread.join(timeout=10)


def drag(browser, url: str, moves: int, hz: float) -> tuple[list[dict], int]:
    """One drag of contrast's c in a fresh page: `moves` mouse positions at `hz`, then the
    release; waits (up to 60 s) for the image at rest.

    Returns:
        (the page's latency entries, the input events the drag fired).
    """
    page = browser.new_page()
    try:
        page.goto(url)
        page.wait_for_function("document.getElementById('image').dataset.stamp !== undefined",
                               timeout=60_000)
        page.select_option("#style", "contrast")
        page.wait_for_function("document.getElementById('command').value"
                               ".includes('--style contrast')", timeout=60_000)
        page.evaluate("""() => { window.inputs = 0; window.latencies.length = 0;
            document.querySelector('[data-param="c"]').addEventListener(
              'input', () => window.inputs++); }""")
        box = page.locator('[data-param="c"]').bounding_box()
        y = box["y"] + box["height"] / 2
        page.mouse.move(box["x"] + 0.1 * box["width"], y)
        page.mouse.down()
        start = time.perf_counter()
        for k in range(1, moves + 1):
            page.mouse.move(box["x"] + (0.1 + 0.8 * k / moves) * box["width"], y)
            time.sleep(max(0.0, start + k / hz - time.perf_counter()))
        page.mouse.up()
        page.wait_for_function("window.latencies.some((x) => !x.quick)", timeout=60_000)
        return page.evaluate("() => window.latencies"), page.evaluate("() => window.inputs")
    finally:
        page.close()


def measure(runs: int, moves: int, hz: float) -> dict:
    """Every run's latency entries (module doc) and the session's facts."""
    from playwright.sync_api import sync_playwright

    from styletrace.preview.jobs import page_job
    from styletrace.preview.session import Session
    load = os.getloadavg()  # before this script's own render
    session = Session(page_job(SCENE, width=SIZE, height=SIZE)).start()
    session.join()
    if session.error:
        raise SystemExit(f"preview_latency: the session failed: {session.error}")
    out = {"state": session.state(), "load_before": load, "runs": []}
    try:
        with served(session) as url, sync_playwright() as pw:
            browser = pw.chromium.launch(executable_path=CHROMIUM, headless=True,
                                         args=["--no-sandbox"])
            drag(browser, url, moves, hz)  # untimed: contrast's kernels compiled
            for _ in range(runs):
                out["runs"].append(drag(browser, url, moves, hz))
            browser.close()
    finally:
        session.stop()
    out["load_after"] = os.getloadavg()
    return out


def ms(values: list[float]) -> str:
    return f"{statistics.median(values):.1f} ms (largest {max(values):.1f})"


def report(m: dict, runs: int, moves: int, hz: float) -> str:
    quick = [x for entries, _ in m["runs"] for x in entries if x["quick"]]
    rest = [x for entries, _ in m["runs"] for x in entries if not x["quick"]]
    inputs = sum(n for _, n in m["runs"])
    st = m["state"]
    med = statistics.median(x["ms"] for x in quick)
    worst = max(x["ms"] for x in quick)
    verdict = ("met" if worst <= GOAL_MS else
               "met by the median, not by the largest" if med <= GOAL_MS else "not met")
    load = "load average (1 min) {:.1f} before the run, {:.1f} after it".format(
        m["load_before"][0], m["load_after"][0])
    def part(a: str, b: str) -> str:
        return ms([x[b] - x[a] for x in quick])

    rows = [
        "| measured | median (largest) |",
        "|---|---|",
        "| **dragged value: input event to the frame that shows it** | "
        f"**{ms([x['ms'] for x in quick])}** |",
        f"| its parts: waiting for the request before it | {part('input', 'sent')} |",
        f"| sent to its answer's headers in | {part('sent', 'answered')} |",
        f"| its pixels in (1 MiB) | {part('answered', 'received')} |",
        f"| drawn (`putImageData`) | {part('received', 'drawn')} |",
        f"| drawn to the frame painted | {part('drawn', 'shown')} |",
        f"| its server time (restyle, 8-bit sRGB RGBA answer) | "
        f"{ms([x['server_ms'] for x in quick])} |",
        f"| its restyle alone (one point per pixel) | {ms([x['restyle_ms'] for x in quick])} |",
        f"| at rest: the release's change event to the whole buffer's restyle shown | "
        f"{ms([x['ms'] for x in rest])} |",
        f"| at rest: its server time | {ms([x['server_ms'] for x in rest])} |",
    ]
    return "\n".join([
        "## Preview: a dragged value, input to screen (`benchmarks/preview_latency.py`)",
        "",
        f"`styletrace preview {SCENE} --width {SIZE} --height {SIZE}` at the defaults "
        f"(style {st['initial']['style']}: {st['samples']} samples = {st['spp']} camera samples "
        f"x {st['children']} children, denoised: {st['method']}), its schedule done; headless "
        f"Chromium drags contrast's `c` ({moves} mouse positions at {hz:g} Hz, then the release), "
        f"{runs} drags after an untimed one. Times are the page's own (`window.latencies`): from "
        "a value's `input` event to the frame that paints it (a task posted from that frame's "
        "animation callback; the compositor's present follows); the server's from the "
        "request's arrival to its answer ready. The answer is the image's raw pixels (8-bit "
        "sRGB RGBA, 1 MiB at 512²) drawn with `putImageData`; one request at the server at a "
        "time, the next (the newest value) sent once an answer's headers are in. Medians and "
        "largest of each part are taken apart, so they do not add up.",
        "",
        *rows,
        "",
        f"{sum(x['ms'] <= GOAL_MS for x in quick)} of the {len(quick)} dragged values shown were "
        f"on screen within {GOAL_MS:.0f} ms of their input; "
        f"{len(quick)} values shown of {inputs} input events (the others were "
        "superseded while a request was out; the oldest value waiting times the next image "
        f"shown, `docs/preview.md`). Goal (issue 44): on screen within {GOAL_MS:.0f} ms: "
        f"**{verdict}**. Issue 44 reported 93 to 305 ms for this drag with the answer before "
        "(a PNG data URL in JSON) and a restyle of about 9 ms.",
        "",
        f"Machine: {machine_description()}; {load} (other people's work shares its 2 cores).",
    ])


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--runs", type=int, default=3, help="timed drags (default 3)")
    ap.add_argument("--moves", type=int, default=30, help="mouse positions a drag (default 30)")
    ap.add_argument("--hz", type=float, default=60.0, help="mouse positions a second (default 60)")
    ap.add_argument("--no-write", action="store_true", help="print, do not write BENCHMARKS.md")
    args = ap.parse_args()
    styletrace.init()
    body = report(measure(args.runs, args.moves, args.hz), args.runs, args.moves, args.hz)
    print(body)
    if not args.no_write:
        write_section("preview_latency", body)


if __name__ == "__main__":
    main()
