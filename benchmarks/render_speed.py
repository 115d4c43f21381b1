"""Speed and memory of the `stylized` integrator against Mitsuba's own `path`, measured in one run.

For each built-in scene at 256x256: `stylized` at S camera samples with n inner samples per first
hit, timed against `path` at S*n samples per pixel (the same number of light paths; the stylized
tree shares each camera ray and first intersection among its n children).

Protocol: every configuration renders once untimed (kernel compilation), then `--runs` rounds
follow; a round renders `path`, identity and cel once each, in an order rotated from round to round,
so that a change of machine load hits all of them. Each render's wall time and CPU time (this
process's user + system time, Dr.Jit's worker threads included) are recorded; the ratios stylized /
`path` are paired within a round. The table gives medians with the min-max range over the rounds.
The styles' scene-relative 'auto' values (cel's thresholds: a small `path` pilot) are resolved
before the timing, as a render resolves them before its first pass; the pilot's own time is reported
apart. The load average before and after is written with the numbers: ratios measured on a busy
machine are noisy (the CPU-time ratio less so).

After the timed rounds, one more render per configuration runs with Dr.Jit's kernel history on: its
wall time split into tracing + Mitsuba's film work (the rest), code generation, LLVM compilation (0
on a kernel cache hit) and kernel execution, and the IR operation count of the largest kernel (the
megakernel).

Peak memory is the maximum resident set size of a separate process rendering 512x512 at S=64, n=64
(683 s on 2 cores): it runs only with `--memory`; otherwise the section keeps the previous line.

    # 5 rounds, memory line kept (about 5 min on 2 idle cores)
    .venv/bin/python benchmarks/render_speed.py
    # the same (explicit: no memory run)
    .venv/bin/python benchmarks/render_speed.py --quick
    # also re-measures peak memory (+ about 12 min)
    .venv/bin/python benchmarks/render_speed.py --memory
"""

from __future__ import annotations

import argparse
import os
import re
import resource
import statistics
import subprocess
import sys
import time

from _report import REPORT, machine_description, write_section

import styletrace
from styletrace.frontends.api import load_scene, make_integrator, passes, resolve_defaults
from styletrace.gate import dr, mi

styletrace.init()  # first: it points Dr.Jit at a working libLLVM

RES = 256
S, N = 16, 8
SCENES = ("cornell-box", "dragon")
STYLES = ("identity", "cel")
#: a machine whose 1-minute load average exceeds this at the start is not idle: the section says so
IDLE_LOAD = 0.5


def cpu_seconds() -> float:
    r = resource.getrusage(resource.RUSAGE_SELF)
    return r.ru_utime + r.ru_stime


def render(scene, integrator, spp, seed):
    for _ in passes(scene, integrator, spp, seed=seed):
        pass


def timed(scene, integrator, spp, runs):
    """Median wall time of `runs` renders after one warm-up render, and the times (media_speed.py
    uses it)."""
    render(scene, integrator, spp, 99)  # warm-up: compile and cache the kernels
    times = []
    for r in range(runs):
        t = time.perf_counter()
        render(scene, integrator, spp, r)
        times.append(time.perf_counter() - t)
    return statistics.median(times), times


def measure(scene, integrator, spp, seed):
    """(wall s, CPU s) of one render."""
    t, c = time.perf_counter(), cpu_seconds()
    render(scene, integrator, spp, seed)
    return time.perf_counter() - t, cpu_seconds() - c


def profile(scene, integrator, spp, seed) -> dict:
    """One render with Dr.Jit's kernel history: where its wall time goes (seconds) and the
    kernels' sizes."""
    dr.kernel_history_clear()
    with dr.scoped_set_flag(dr.JitFlag.KernelHistory, True):
        t = time.perf_counter()
        render(scene, integrator, spp, seed)
        wall = time.perf_counter() - t
        hist = dr.kernel_history()
    jit = [h for h in hist if h["type"] == dr.KernelType.JIT]
    sec = lambda hs, key: sum(float(h.get(key, 0.0)) for h in hs) / 1e3  # noqa: E731 (ms -> s)
    out = dict(
        wall=wall,
        launches=len(jit),
        codegen=sec(jit, "codegen_time"),
        llvm=sec(jit, "backend_time"),
        execution=sec(jit, "execution_time"),
        other=sec([h for h in hist if h["type"] != dr.KernelType.JIT], "execution_time"),
        ops=max(int(h["operation_count"]) for h in jit),
    )
    out["trace"] = wall - out["codegen"] - out["llvm"] - out["execution"] - out["other"]
    return out


def spread(xs, fmt="{:.2f}") -> str:
    """median [min-max]"""
    return f"{fmt.format(statistics.median(xs))} [{fmt.format(min(xs))}-{fmt.format(max(xs))}]"


MEMORY_CODE = """
import resource, sys, time
sys.path.insert(0, {src!r})
import styletrace
t = time.perf_counter()
styletrace.render('cornell-box', style='cel', spp=64, inner=64, width=512, height=512)
print(time.perf_counter() - t, resource.getrusage(resource.RUSAGE_SELF).ru_maxrss)
"""


def peak_memory():
    src = os.path.join(os.path.dirname(__file__), "..", "src")
    out = subprocess.run(
        [sys.executable, "-c", MEMORY_CODE.format(src=os.path.abspath(src))],
        capture_output=True,
        text=True,
        check=True,
    ).stdout.split()
    return float(out[0]), int(out[1]) / 1024.0  # seconds, MiB (ru_maxrss is in KiB on Linux)


def previous_memory_line() -> str | None:
    """The peak-memory line of the section as it stands in BENCHMARKS.md (kept when memory is not
    re-run)."""
    if not REPORT.exists():
        return None
    m = re.search(
        r"<!-- section:render_speed -->(.*?)<!-- /section:render_speed -->",
        REPORT.read_text(),
        re.S,
    )
    if not m:
        return None
    text = m.group(1)
    commit = re.search(r"commit (\w+)\.", text)
    for line in text.splitlines():
        if line.startswith("Peak memory"):
            if "not re-measured" in line:  # already marked by an earlier run
                return line
            at = f"measured at commit {commit.group(1)}; " if commit else ""
            return line + f" ({at}not re-measured in this run: `--memory` does)"
    return None


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument(
        "--runs", type=int, default=5, help="timed rounds after the warm-up (default 5)"
    )
    ap.add_argument(
        "--quick", action="store_true", help="no peak-memory run (the default): keep the old line"
    )
    # the old spelling of --quick
    ap.add_argument("--skip-memory", action="store_true", help=argparse.SUPPRESS)
    ap.add_argument(
        "--memory", action="store_true", help="also re-measure peak memory (about 12 min)"
    )
    args = ap.parse_args()

    load_before = os.getloadavg()
    print(
        f"load average at start: {load_before[0]:.2f} {load_before[1]:.2f} {load_before[2]:.2f}",
        flush=True,
    )
    rows, profiles, pilots = [], {}, {}
    for name in SCENES:
        scene = load_scene(name, RES, RES)
        configs = {"path": (mi.load_dict({"type": "path"}), S * N)}
        for style in STYLES:
            integ = make_integrator(style, inner=N)
            t = time.perf_counter()
            # cold: traces (and compiles) the pilot if a rule needs one
            resolved, _ = resolve_defaults(scene, integ)
            cold = time.perf_counter() - t
            warm = []
            for _ in range(3):
                t = time.perf_counter()
                resolve_defaults(scene, integ)
                warm.append(time.perf_counter() - t)
            pilots[name, style] = (cold, min(warm))
            configs[style] = (resolved, S)
        for integ, spp in configs.values():  # warm-up: compile and cache the kernels
            render(scene, integ, spp, 99)
        names = list(configs)
        times = {k: [] for k in names}
        for r in range(args.runs):
            k = r % len(names)
            for key in names[k:] + names[:k]:
                times[key].append(measure(scene, *configs[key], seed=r))
            print(
                name,
                f"round {r}:",
                ", ".join(f"{key} {times[key][-1][0]:.2f} s" for key in names),
                f"(load {os.getloadavg()[0]:.2f})",
                flush=True,
            )
        for key in names:
            profiles[name, key] = profile(scene, *configs[key], seed=0)
        path = times["path"]
        for style in STYLES:
            ours = times[style]
            rows.append(
                dict(
                    scene=name,
                    style=style,
                    wall=[w for w, _ in ours],
                    path=[w for w, _ in path],
                    ratio=[a[0] / b[0] for a, b in zip(ours, path)],
                    cpu_ratio=[a[1] / b[1] for a, b in zip(ours, path)],
                )
            )
    load_after = os.getloadavg()

    paths = RES * RES * S * N
    lines = [
        "## Stylized integrator vs Mitsuba `path` (`benchmarks/render_speed.py`)",
        "",
        f"Machine: {machine_description()}.",
        "",
        f"Load average (1, 5, 15 min) at start {load_before[0]:.2f}, {load_before[1]:.2f}, "
        f"{load_before[2]:.2f}; "
        f"at end {load_after[0]:.2f}, {load_after[1]:.2f}, {load_after[2]:.2f}.",
    ]
    if load_before[0] > IDLE_LOAD:
        lines += [
            "",
            f"**Warning: the machine was not idle (load average {load_before[0]:.2f} > "
            f"{IDLE_LOAD} at "
            "start): the times and wall-time ratios below are noisy; the CPU-time ratio is the "
            "steadier "
            "one. Re-run on an idle machine for the record.**",
        ]
    lines += [
        "",
        f"{RES}x{RES}, `stylized` at S={S} camera samples x n={N} inner samples vs `path` at "
        f"{S * N} spp "
        f"(same number of light paths), max_depth unbounded, Russian roulette from depth 5. One "
        f"untimed warm-up "
        f"render per configuration, then {args.runs} rounds, each rendering `path`, identity and "
        f"cel once in an "
        f"order rotated per round; median [min-max] over the rounds, ratios paired within a "
        f"round. CPU = this "
        f"process's user + system time (both Dr.Jit worker threads). cel's auto thresholds are "
        f"resolved before "
        f"timing (their pilot is not in the times, see below). Targets: identity ratio <= 1.0, "
        f"cel ratio <= 1.05.",
        "",
        "| scene | style | stylized (s) | path (s) | ratio (wall) | ratio (CPU) | stylized M "
        "paths/s |",
        "|---|---|---|---|---|---|---|",
    ]
    for row in rows:
        lines.append(
            f"| {row['scene']} | {row['style']} | {spread(row['wall'])} | {spread(row['path'])} | "
            f"{spread(row['ratio'], '{:.3f}')} | {spread(row['cpu_ratio'], '{:.3f}')} | "
            f"{paths / statistics.median(row['wall']) / 1e6:.2f} |"
        )

    lines += [
        "",
        "Where the time goes: one more render per configuration with Dr.Jit's kernel history on "
        "(seconds; "
        "trace = Python tracing of the kernels plus Mitsuba's film and the pass loop, i.e. the "
        "wall time "
        "less the rest; LLVM = compilation, 0 on a kernel-cache hit; ops = IR operations of the "
        "largest "
        "kernel):",
        "",
        "| scene | integrator | wall | trace | codegen | LLVM | execution | launches | ops |",
        "|---|---|---|---|---|---|---|---|---|",
    ]
    for (name, key), p in profiles.items():
        lines.append(
            f"| {name} | {key} | {p['wall']:.2f} | {p['trace']:.3f} | {p['codegen']:.3f} | "
            f"{p['llvm']:.3f} | "
            f"{p['execution']:.2f} | {p['launches']} | {p['ops']} |"
        )
    cb = {k: profiles["cornell-box", k] for k in ("path", "identity", "cel")}
    per_round = {row["scene"]: {} for row in rows}
    for row in rows:
        per_round[row["scene"]][row["style"]] = row["cpu_ratio"]
    cel_vs_identity = "; ".join(
        f"{name} {spread([c / i for c, i in zip(r['cel'], r['identity'])], '{:.3f}')}"
        for name, r in per_round.items()
    )
    cold, warm = pilots["cornell-box", "cel"]
    lines += [
        "",
        "Reading: kernel execution is "
        f"{100 * cb['cel']['execution'] / cb['cel']['wall']:.1f}% of a cel render's wall time on "
        f"the Cornell box; "
        f"tracing, code generation and LLVM (after the warm-up every kernel is a cache hit) take "
        f"{cb['cel']['trace'] + cb['cel']['codegen'] + cb['cel']['llvm']:.3f} s together. cel's "
        f"megakernel has "
        f"{cb['cel']['ops'] - cb['identity']['ops']:+d} IR operations against identity's "
        f"({cb['cel']['ops']} vs {cb['identity']['ops']}): g (brightness, one select per "
        f"threshold, a division) "
        f"runs once per camera sample after the loop over the n children, whose code is the same "
        f"as identity's; "
        f"the thresholds are constants in the kernel, there is no search at render time. The "
        f"auto-threshold "
        f"pilot (resolve_defaults, before the first pass) took {cold:.3f} s at its first call in "
        f"this process "
        f"(its kernels compiled, or loaded from Dr.Jit's disk cache) and {warm:.3f} s later (min "
        f"of 3); a render "
        f"runs it once, before its first pass. Before this protocol (commit 33412e0) each "
        f"configuration was timed "
        f"in a block of 3 runs, `path` first, with that pilot inside each cel run's timed region "
        f"(under 1% of "
        f"it); that run read cel 1.157 and identity 0.992 on a shared machine. cel / identity CPU "
        f"time, paired per round: {cel_vs_identity} (median [min-max]). So cel costs what "
        f"identity costs to "
        f"within about that ratio, and a larger gap between their wall-time ratios is load noise "
        f"(compare the "
        f"CPU ratios and the load average).",
    ]

    if args.memory:
        secs, mib = peak_memory()
        lines += [
            "",
            f"Peak memory (max RSS of a fresh process, Python + Mitsuba + kernels), cornell-box "
            f"at 512x512, "
            f"cel, S=64, n=64 ({512 * 512 * 64 * 64 / 1e9:.2f} G light paths): **{mib:.0f} MiB** "
            f"in {secs:.0f} s. Target <= 1 GB.",
        ]
    else:
        old = previous_memory_line()
        if old:
            lines += ["", old]
    write_section("render_speed", "\n".join(lines))
    print("\n".join(lines))


if __name__ == "__main__":
    main()
