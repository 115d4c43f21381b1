"""Shared plumbing for the benchmark scripts: one BENCHMARKS.md, one section per script.

Each script owns the text between its own markers, so scripts can be re-run in any order
without clobbering each other's measurements.
"""
from __future__ import annotations

import os
import platform
import re
import subprocess
from pathlib import Path

REPORT = Path(__file__).resolve().parent.parent / "BENCHMARKS.md"
HEADER = (
    "# styletrace benchmarks\n\nEach section is written by the script named in it; re-run "
    "that script to refresh it.\n"
)


def machine_description() -> str:
    """One paragraph naming the CPU, core count, memory and the versions that shape the numbers."""
    cpu = platform.processor() or "unknown CPU"
    try:
        with open("/proc/cpuinfo") as f:
            for line in f:
                if line.startswith("model name"):
                    cpu = line.split(":", 1)[1].strip()
                    break
    except OSError:
        pass
    mem = ""
    try:
        with open("/proc/meminfo") as f:
            kb = int(f.readline().split()[1])
            mem = f", {kb / 2**20:.0f} GiB RAM"
    except (OSError, ValueError, IndexError):
        pass
    versions = [f"Python {platform.python_version()}"]
    for mod in ("mitsuba", "drjit", "numpy"):
        try:
            versions.append(f"{mod} {__import__(mod).__version__}")
        except Exception:  # a section that does not need the module should still be writable
            pass
    try:
        import mitsuba as mi
        if mi.variant():
            versions.append(f"variant {mi.variant()}")
    except Exception:
        pass
    llvm = os.environ.get("DRJIT_LIBLLVM_PATH")
    if llvm:
        versions.append(f"libLLVM {Path(llvm).name}")
    try:
        rev = subprocess.run(
            ["git", "rev-parse", "--short", "HEAD"],
            capture_output=True,
            text=True,
            cwd=REPORT.parent,
            check=False,
        ).stdout.strip()
        if rev:
            versions.append(f"commit {rev}")
    except OSError:
        pass
    return f"{cpu}, {os.cpu_count()} cores{mem}; " + ", ".join(versions)


def write_section(name: str, body: str) -> None:
    """Replace (or append) the section `name` of BENCHMARKS.md with `body`."""
    start, end = f"<!-- section:{name} -->", f"<!-- /section:{name} -->"
    text = REPORT.read_text() if REPORT.exists() else HEADER
    block = f"{start}\n{body.rstrip()}\n{end}"
    pattern = re.compile(re.escape(start) + ".*?" + re.escape(end), re.S)
    text = (
        pattern.sub(lambda _: block, text)
        if pattern.search(text)
        else text.rstrip() + "\n\n" + block + "\n"
    )
    from styletrace.images import write_bytes_atomically  # a cut write never halves the file
    write_bytes_atomically(text.encode(), str(REPORT))


def median_time(fn, runs: int) -> float:
    """Median wall time of `runs` calls of `fn` after one warm-up call (kernels compiled, caches
    filled)."""
    import statistics
    import time
    fn()
    out = []
    for _ in range(runs):
        t = time.perf_counter()
        fn()
        out.append(time.perf_counter() - t)
    return statistics.median(out)


def image_grid(
    panels, path: str, row_height: float = 3.1, fontsize: int = 8, width: float | None = None
) -> None:
    """A figure of images side by side, one row per (title, [(label, linear image), ...]) in
    `panels`, shown in sRGB, the row's title above its first ("reference") image; written
    atomically as every image of the project."""
    import io

    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from styletrace.images import srgb8, write_bytes_atomically
    columns = max(len(cells) for _, cells in panels)
    fig, axes = plt.subplots(
        len(panels),
        columns,
        figsize=(width or 3 * columns, row_height * len(panels)),
        squeeze=False,
    )
    for row, (title, cells) in zip(axes, panels):
        for ax, (label, img) in zip(row, cells):
            ax.imshow(srgb8(img))
            ax.set_title(f"{title}\n{label}" if label == "reference" else label, fontsize=fontsize)
            ax.axis("off")
    fig.tight_layout()
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=100)
    write_bytes_atomically(buf.getvalue(), path)
    plt.close(fig)
