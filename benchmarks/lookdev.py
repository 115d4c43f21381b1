"""Look development: restyle against a fresh render, preview time to first image, buffer memory,
fitting.

- Restyle: the Cornell box at 512x512, 16 camera samples per pixel, n = 16 children, recorded once
  (`render_buffer`); each restyle (cel, colour map, gamma) is warmed up once (kernel compilation),
  then timed `--runs` times (median, end to end: the H x W x 3 numpy image). The fresh render is
  `styletrace.render` with the same settings (one timed run after a warm-up at 64x64).
- Preview: a `Session` of the Cornell box at 256x256 (16 camera samples per pixel, n = 8,
  `preview.jobs.page_job`) and its server, in a fresh process; the time from the server listening to
  the first 200 of /api/restyle (polled every 20 ms: the draft, one camera sample of the n children
  at the draft's size) and to the first restyle of a full-size image (after the first pass). Twice:
  with a cold Dr.Jit kernel cache (HOME pointed at an empty folder, so ~/.drjit is empty) and with a
  warm one.
- Memory: bytes per camera sample of the buffer (numpy) and of its Dr.Jit copy used by restyles.
- Fit: a 128x128, 4 spp, n = 4 buffer; targets restyled with known θ; iterations and seconds until
  the loss reaches 1e-9 (or the 300 iterations end), and the error of the recovered θ.

    .venv/bin/python benchmarks/lookdev.py [--runs 5]
"""
from __future__ import annotations

import argparse
import os
import sys
import threading
import time

import numpy as np
from _report import machine_description, median_time, write_section

import styletrace
from styletrace.lookdev.fit import fit
from styletrace.lookdev.record import render_buffer
from styletrace.lookdev.restyle import device, restyle

styletrace.init()

GREY5 = "0:0.5,0.5,0.5;0.3:0.5,0.5,0.5;0.6:0.5,0.5,0.5;0.9:0.5,0.5,0.5;1.2:0.5,0.5,0.5"


def preview_first_image() -> tuple[float, float]:
    import httpx
    import uvicorn

    from styletrace.preview.jobs import page_job
    from styletrace.preview.server import make_app
    from styletrace.preview.session import Session
    session = Session(page_job("cornell-box", inner=8, spp=16, width=256, height=256))
    srv = uvicorn.Server(
        uvicorn.Config(make_app(session), host="127.0.0.1", port=0, log_level="warning")
    )
    thread = threading.Thread(target=srv.run, daemon=True)
    thread.start()
    while not srv.started:
        time.sleep(0.005)
    t0 = time.perf_counter()
    session.start()
    url = f"http://127.0.0.1:{srv.servers[0].sockets[0].getsockname()[1]}/api/restyle"
    first = full = None
    while full is None:
        r = httpx.post(url, json={"style": "cel", "params": {}}, timeout=60)
        if r.status_code == 200:
            first = first or time.perf_counter() - t0
            if not r.json()["draft"]:
                full = time.perf_counter() - t0
        time.sleep(0.02)
    session.stop()
    srv.should_exit = True
    thread.join(timeout=10)
    return first, full


def preview_in_a_fresh_process(cold: bool) -> tuple[float, float]:
    """`preview_first_image` in a new Python process; cold: with an empty Dr.Jit kernel cache."""
    import json
    import subprocess
    import tempfile
    env = dict(os.environ)
    with tempfile.TemporaryDirectory() as home:
        if cold:
            env["HOME"] = home
        out = subprocess.run([sys.executable, __file__, "--preview-only"], env=env, check=True,
                             capture_output=True, text=True).stdout
    return tuple(json.loads(out.strip().splitlines()[-1]))


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--runs", type=int, default=5)
    ap.add_argument(
        "--preview-only", action="store_true", help="print the preview's times as JSON and stop"
    )
    args = ap.parse_args()
    if args.preview_only:
        import json
        print(json.dumps(preview_first_image()))
        return
    preview_in_a_fresh_process(cold=False)  # fills the kernel cache for the warm measurement
    cold = preview_in_a_fresh_process(cold=True)
    warm = preview_in_a_fresh_process(cold=False)
    kw = dict(spp=16, inner=16, seed=0, width=512, height=512)
    t = time.perf_counter()
    buf = render_buffer("cornell-box", style="cel", **kw)
    record_s = time.perf_counter() - t
    styletrace.render("cornell-box", style="cel", spp=1, inner=16, width=64, height=64)  # compile
    t = time.perf_counter()
    styletrace.render("cornell-box", style="cel", **kw)
    fresh_s = time.perf_counter() - t
    rows = []
    for style, params in (
        ("cel", {}),
        ("color_map", {"gradient": "heat"}),
        ("gamma", {"gamma": 2.2}),
    ):
        s = median_time(lambda: restyle(buf, style=style, **params), args.runs)
        rows.append(f"| {style} | {s * 1e3:.0f} ms | {fresh_s / s:.0f}x |")
    d = device(buf)
    dev_bytes = sum(int(np.asarray(x).nbytes) for k, x in d.items() if k != "inv_weight")

    seq_rows = []
    for style, est in (
        ("gamma", "series"),
        ("gamma", "series_recursive"),
        ("gamma", "series_single"),
        ("gamma", "telescoping"),
        ("tie_dye", "ustat"),
        ("tie_dye", "naive"),
        ("gamma+sepia", "combined"),
    ):
        sb = render_buffer(
            "cornell-box", style=style, estimator=est, spp=4, inner=8, seed=1, width=64, height=64
        )
        kinds = sb.arrays["seq_kind"]
        seq_rows.append(
            f"| {style} | {est} | {kinds.sum() / sb.camera_samples:.1f} | "
            f"{(kinds.size - kinds.sum()) / sb.camera_samples:.1f} "
            f"| {sb.nbytes / sb.camera_samples:.0f} |"
        )

    small = render_buffer("cornell-box", style="cel", spp=4, inner=4, seed=3, width=128, height=128)
    fits = []
    for style, truth, init in (("contrast", {"c": 2.2, "pivot": 0.3}, {}),
                               ("color_map", {"gradient": "heat"}, {"gradient": GREY5}),
                               ("cel", {"thresholds": (0.1, 0.4), "levels": (0.05, 0.3, 0.8)},
                                {"thresholds": (0.2, 0.6), "levels": (0.2, 0.5, 0.6)})):
        r = fit(small, style=style, target=restyle(small, style=style, **truth), **init)
        if style == "color_map":
            err = "stop colours: see tests/lookdev/test_fit.py"
        else:
            err = ", ".join(
                f"{k} {np.max(np.abs(np.subtract(r.params[k], v))):.1e}" for k, v in truth.items()
            )
        fits.append(f"| {style} | {r.iterations} | {r.seconds:.2f} s | {r.loss:.1e} | {err} |")

    lines = [
        "## Look development: restyle, preview, fit (`benchmarks/lookdev.py`)",
        "",
        machine_description(),
        "",
        f"Cornell box 512x512, 16 camera samples per pixel, n = 16 children "
        f"({buf.camera_samples} camera samples). "
        f"Fresh render (`styletrace.render`, cel): {fresh_s:.1f} s; the same render recording the "
        f"buffer: "
        f"{record_s:.1f} s. Restyle, median of {args.runs} after a warm-up (goal: >= 500x faster "
        f"than the "
        f"render, <= 100 ms for cel and colour map):",
        "",
        "| style | restyle | faster than the fresh render |",
        "|---|---|---|",
        *rows,
        "",
        f"Buffer memory: {buf.nbytes / buf.camera_samples:.0f} bytes per camera sample in the file "
        f"and in numpy "
        f"({buf.nbytes / 2**20:.0f} MiB here), plus {dev_bytes / buf.camera_samples:.0f} bytes per "
        f"sample for the Dr.Jit "
        f"copy restyles work on; the default cap of 4194304 camera samples bounds both.",
        "",
        f"Preview, Cornell box 256x256 (16 camera samples per pixel, n = 8), each in a fresh "
        f"process, time after the server listens (goal: first image <= 3 s). Warm kernel cache "
        f"(~/.drjit filled by an earlier run): first image {warm[0]:.2f} s (the draft: one camera "
        f"sample of n = 8 at the draft's size), first full-size image (after the first pass of "
        f"one camera sample) {warm[1]:.2f} s. Cold cache (empty ~/.drjit, every kernel compiled): "
        f"first image {cold[0]:.2f} s, first full-size image {cold[1]:.2f} s.",
        "",
        "Sequence buffers (the unbiased estimators; docs/lookdev.md): Cornell box 64x64, 4 spp, n "
        "= 8, bytes per "
        "camera sample = 57 + 13 per child + 5 per uniform:",
        "",
        "| style | estimator | children per sample | uniforms per sample | bytes per sample |",
        "|---|---|---|---|---|",
        *seq_rows,
        "",
        "Fit on a 128x128, 4 spp, n = 4 buffer to targets restyled with known θ (Adam, 300 "
        "iterations at most, "
        "stopping at a loss of 1e-9):",
        "",
        "| style | iterations | time | final MSE | largest θ error |",
        "|---|---|---|---|---|",
        *fits,
    ]
    write_section("lookdev", "\n".join(lines))
    print("\n".join(lines))


if __name__ == "__main__":
    main()
