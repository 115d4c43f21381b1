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
HEADER = "# styletrace benchmarks\n\nEach section is written by the script named in it; re-run that script to refresh it.\n"


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
        rev = subprocess.run(["git", "rev-parse", "--short", "HEAD"], capture_output=True, text=True,
                             cwd=REPORT.parent, check=False).stdout.strip()
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
    text = pattern.sub(lambda _: block, text) if pattern.search(text) else text.rstrip() + "\n\n" + block + "\n"
    REPORT.write_text(text)


def median_time(fn, runs: int) -> float:
    """Median wall time of `runs` calls of `fn` after one warm-up call (kernels compiled, caches filled)."""
    import statistics
    import time
    fn()
    out = []
    for _ in range(runs):
        t = time.perf_counter()
        fn()
        out.append(time.perf_counter() - t)
    return statistics.median(out)
