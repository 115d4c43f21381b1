"""Peak memory of `styletrace render` by image size: tiles and a float32 accumulator keep it
bounded.

Each size runs in a fresh process (`python -m styletrace render cornell-box --style cel --inner 1
--spp S -o out.exr`), and the peak resident set size is that child's ru_maxrss. The largest, 8192 x
8192 at spp 4, is 64 tiles of 1024 x 1024; before tiling it was one pass of 67 M lanes and went past
6 GB. The estimate is `api.memory_needed`, what the command line checks against the available memory
before it loads anything heavy.

    .venv/bin/python benchmarks/memory.py [--sizes 256,1024,2048,8192] [--spp 4]
"""
from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tempfile
import time

from _report import machine_description, write_section

HERE = os.path.dirname(os.path.abspath(__file__))
SRC = os.path.join(HERE, "..", "src")

CHILD = """
import resource, subprocess, sys, time
t = time.perf_counter()
code = subprocess.run([sys.executable, "-m", "styletrace", *sys.argv[1:]]).returncode
print(code, time.perf_counter() - t, resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss)
"""


def peak(size: int, spp: int) -> tuple[float, float]:
    """(seconds, peak RSS in MiB) of one render in its own process."""
    with tempfile.TemporaryDirectory() as tmp:
        args = [
            "render",
            "cornell-box",
            "--style",
            "cel",
            "--inner",
            "1",
            "--spp",
            str(spp),
            "--width",
            str(size),
            "--height",
            str(size),
            "-q",
            "-o",
            os.path.join(tmp, "out.exr"),
        ]
        env = dict(
            os.environ,
            PYTHONPATH=os.pathsep.join(
                p for p in (os.path.abspath(SRC), os.environ.get("PYTHONPATH")) if p
            ),
        )
        out = subprocess.run(
            [sys.executable, "-c", CHILD, *args],
            capture_output=True,
            text=True,
            env=env,
            check=True,
        ).stdout.split()
    code, secs, kib = int(out[0]), float(out[1]), int(out[2])
    if code != 0:
        raise SystemExit(f"render at {size} failed with status {code}")
    return secs, kib / 1024.0


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--sizes", default="256,1024,2048,8192")
    ap.add_argument("--spp", type=int, default=4)
    args = ap.parse_args()

    import styletrace
    styletrace.init()
    from styletrace.frontends import api

    rows = []
    for size in (int(s) for s in args.sizes.split(",")):
        secs, mib = peak(size, args.spp)
        est = api.memory_needed(size, size, ".exr") / 2**20
        rows.append((size, len(api.tiles(size, size)), secs, mib, est))
        print(rows[-1], flush=True)
    lines = [
        "## Peak memory by image size (`benchmarks/memory.py`)",
        "",
        f"`styletrace render cornell-box --style cel --inner 1 --spp {args.spp} -o out.exr` in a "
        f"fresh process per "
        f"size; peak resident set size of that process (ru_maxrss), including Python, Mitsuba, "
        f"the kernels and "
        f"writing the EXR. Images over 2^20 pixels render as 1024 x 1024 tiles; the running sum "
        f"is one float32 "
        f"image. The estimate is `api.memory_needed`, which the command line compares with the "
        f"available memory "
        f"before rendering. Seconds are indicative only: the cores were shared with other jobs "
        f"during the run.",
        "",
        "| size | tiles | seconds | peak RSS (MiB) | estimate (MiB) |",
        "|---|---|---|---|---|",
    ]
    lines += [
        f"| {s}x{s} | {t} | {secs:.0f} | {mib:.0f} | {est:.0f} |" for s, t, secs, mib, est in rows
    ]
    lines += ["", f"Machine: {machine_description()}.", "",
              f"Measured {time.strftime('%Y-%m-%d')}."]
    write_section("memory", "\n".join(lines))


if __name__ == "__main__":
    main()
