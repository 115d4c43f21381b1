"""Cost of feature lines (kernel/lines.py, docs/lines.md): render time with lines against without.

The colour map style at n = 8 samples per style evaluation on the dragon and on the mirror/glass
scene (`lines`), with lines off, and on at N = 8 and 16 auxiliary rays per tested edge, at
line_depth 1 (the camera ray) and 3 (also two edges below: mirror and glass). The LLaT expectation
mode (k = 12) is timed with its short-circuit (lanes where a stencil pair fires trace no radiance)
and without it, which is what the short-circuit saves. Each configuration renders once to compile,
then the median of RUNS warm renders is taken, the configurations of a scene timed in turn in each
round (one process per scene) so that a change of the machine's load falls on all of them alike.

    .venv/bin/python benchmarks/lines_cost.py
"""
from __future__ import annotations

import json
import os
import subprocess
import sys

from _report import machine_description, write_section

SRC = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", "src"))
RES, SPP, INNER, RUNS = 128, 4, 8, 7
LINES = [
    ("off", {}),
    ("N=8, depth 1", {"lines": True, "line_samples": 8, "line_depth": 1}),
    ("N=16, depth 1", {"lines": True, "line_samples": 16, "line_depth": 1}),
    ("N=8, depth 3", {"lines": True, "line_samples": 8, "line_depth": 3}),
    ("N=16, depth 3", {"lines": True, "line_samples": 16, "line_depth": 3}),
    ("expectation k=12, short-circuit", {"lines": True, "line_mode": "expectation", "line_k": 12}),
    (
        "expectation k=12, no short-circuit",
        {"lines": True, "line_mode": "expectation", "line_k": 12, "_no_short_circuit": True},
    ),
]

CHILD = """
import json, statistics, sys, time
sys.path.insert(0, {src!r})
import styletrace
from styletrace.frontends.api import load_scene, make_integrator, render
scene = load_scene({scene!r}, {res}, {res})
configs = {configs!r}
integs = []
for name, values in configs:
    values = dict(values)
    slow = values.pop('_no_short_circuit', False)
    integ = make_integrator('color_map', inner={inner}, **values)
    integ.line_short_circuit = not slow
    render(scene, integrator=integ, spp={spp}, seed=1)   # compile
    integs.append(integ)
# rounds that time every configuration once each, so that a change of the machine's load hits all \
alike
times, cpu = [[] for _ in configs], [[] for _ in configs]
for r in range({runs}):
    for i, integ in enumerate(integs):
        t, c = time.perf_counter(), time.process_time()
        render(scene, integrator=integ, spp={spp}, seed=1)
        times[i].append(time.perf_counter() - t)
        cpu[i].append(time.process_time() - c)
out = []
for (name, values), ts, cs in zip(configs, times, cpu):
    row = {{'name': name, 'seconds': statistics.median(ts), 'cpu': statistics.median(cs)}}
    if values.get('lines'):  # the share of camera samples a line took: two line colours, one seed
        v = {{k: x for k, x in values.items() if k not in ('line_color', '_no_short_circuit')}}
        a = render(scene, integrator=make_integrator('color_map', inner={inner}, **v, \
line_color='0,0,0'), spp={spp}, seed=1)
        b = render(scene, integrator=make_integrator('color_map', inner={inner}, **v, \
line_color='0,1000,0'), spp={spp}, seed=1)
        row['line_share'] = float((b[..., 1] - a[..., 1]).mean() / 1000.0)
    out.append(row)
print(json.dumps(out))
"""


def measure(scene: str) -> list:
    code = CHILD.format(
        src=SRC, configs=LINES, scene=scene, res=RES, spp=SPP, inner=INNER, runs=RUNS
    )
    out = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, check=True
    ).stdout
    return json.loads(out.strip().splitlines()[-1])


def main():
    rows = []
    for scene in ("dragon", "lines"):
        results = measure(scene)
        base = results[0]["cpu"]
        for r in results:
            rows.append(
                (scene, r["name"], r["seconds"], r["cpu"], r["cpu"] / base, r.get("line_share"))
            )
            print(rows[-1], flush=True)
    load = os.getloadavg()[0]
    text = [
        "## Feature lines: cost (`benchmarks/lines_cost.py`)",
        "",
        f"Machine: {machine_description()}. The machine was shared with other engineers' jobs "
        f"while this ran "
        f"(load average {load:.1f} on {os.cpu_count()} cores at the end): wall times are inflated "
        f"by the "
        f"others' work, so the ratios use the process's CPU time (all its threads), which the "
        f"load disturbs "
        f"less, and compare medians of renders timed in turn, round after round.",
        "",
        f"`color_map` at n = {INNER}, {RES}x{RES}, {SPP} camera samples per pixel, first hit; the "
        f"median of "
        f"{RUNS} warm renders (taken in rounds, every configuration once per round). Line share: "
        f"the fraction of camera samples that a line took (their radiance is "
        f"not traced).",
        "",
        "| scene | lines | wall time (s) | CPU time (s) | CPU time vs. off | line share |",
        "|---|---|---|---|---|---|",
    ]
    for scene, name, secs, cpu, ratio, share in rows:
        text.append(f"| {scene} | {name} | {secs:.2f} | {cpu:.2f} | {ratio:.2f} | "
                    f"{'' if share is None else f'{share:.3f}'} |")
    by = {(s, n): c for s, n, _, c, _, _ in rows}
    notes = []
    for scene in ("dragon", "lines"):
        on, off = by[(scene, "N=8, depth 1")], by[(scene, "off")]
        notes.append(
            f"{scene}: lines at N = 8 cost {on / off:.2f}x the render without (target <= 1.5x)"
        )
        fast, slow = (
            by[(scene, "expectation k=12, short-circuit")],
            by[(scene, "expectation k=12, no short-circuit")],
        )
        notes.append(
            f"{scene}: the expectation mode's short-circuit saves {100 * (1 - fast / slow):.0f}% "
            f"({slow:.2f} s -> {fast:.2f} s CPU)"
        )
    text += [
        "",
        "; ".join(notes) + ".",
        "",
        "Reading: at n = 8 the eight child paths of each camera sample dominate the cost; the N "
        "auxiliary "
        "rays per tested edge are a few rays more, and a camera sample that a line takes traces no "
        "children at all (absorb mode as well as expectation mode), which pays back part of it. "
        "Where "
        "a 'vs. off' ratio is below 1 or the short-circuit's saving is negative, the difference is "
        "smaller than the shared machine's noise, not a measured gain; the line share says how "
        "many "
        "camera samples skipped their children.",
    ]
    write_section("lines_cost", "\n".join(text))
    print("\n".join(text))


if __name__ == "__main__":
    main()
