"""The gallery's equal-time section: one method against the tree sampler's fixed counts at the
same time.

Protocol, per comparison (benchmarks/equal_time.py's, one seed): every render, the reference
(direct application, a large inner count) included, is 1 camera sample per pixel with seed 0, so
the error is the stylized estimate's. Time: the median wall-clock seconds of `repeats` renders (1
in quick mode) after one untimed render that compiles the kernels. The method is timed first, then
the fixed counts n in increasing order until one is slower; the count at equal time is the largest
n not slower than the method (else the smallest, marked). ratio = MSE(fixed n) / MSE(method); the
verdict is "win" only when ratio > 1. Each comparison writes KEY.png and a `gallery.json` entry
(`compare`). Design: docs/design/equal_time.md.
"""
from __future__ import annotations

import html
import io
import os
import statistics
import textwrap
import time
from dataclasses import dataclass, field
from typing import Any, Callable

import numpy as np

from styletrace.images import mse

#: camera samples per pixel and seed of every render of the section (module docstring)
SPP = 1
SEED = 0
#: quick mode: the reference's children per pixel at most (split evenly over its levels), and the
#: number of fixed counts at most (the smallest ones)
QUICK_REFERENCE = 64
QUICK_COUNTS = 3


@dataclass(frozen=True)
class Comparison:
    key: str                            # file name and --only key
    title: str
    style: str
    method: dict[str, Any]              # integrator keywords of the method (inner, reuse, ...)
    reference: int | tuple[int, ...]    # inner count(s) of the reference, direct application
    params: dict[str, Any] = field(default_factory=dict)      # the style's parameters
    # keywords shared by every render (stylize, ...)
    integrator: dict[str, Any] = field(default_factory=dict)
    counts: tuple[int, ...] = (4, 8, 16, 32, 64, 128)         # fixed first-level counts n, doubling
    # the fixed renders' counts at the deeper levels, held constant
    below: tuple[int, ...] = ()
    scene: str = "cornell-box"


def levels(inner: int | tuple[int, ...]) -> tuple[int, ...]:
    """A count as the tuple of its levels' counts.

    Args:
        inner: an inner count, or one per level.

    Returns:
        The counts, a tuple (of one for a single count).
    """
    return tuple(inner) if isinstance(inner, (tuple, list)) else (inner,)


def fixed_inner(c: Comparison, n: int) -> int | tuple[int, ...]:
    """The inner count of the fixed render at first-level count n.

    Args:
        c: the comparison. n: the first-level count.

    Returns:
        n, or (n, *c.below) where the deeper levels' counts are held constant.
    """
    return (n, *c.below) if c.below else n


def quick(c: Comparison) -> Comparison:
    """The comparison in quick mode.

    A small reference (QUICK_REFERENCE children per pixel at most) and at most QUICK_COUNTS fixed
    counts, all below the reference's: a fixed count equal to the reference's would share its
    children (same seed) and measure no error at all.

    Args:
        c: the comparison.

    Returns:
        The quick Comparison.
    """
    ref = levels(c.reference)
    cap = max(1, int(round(QUICK_REFERENCE ** (1 / len(ref)))))
    small = tuple(min(n, cap) for n in ref)
    counts = tuple(n for n in c.counts if n < small[0])[:QUICK_COUNTS] or c.counts[:1]
    return Comparison(
        **{**c.__dict__, "reference": small if len(small) > 1 else small[0], "counts": counts}
    )


def pick(fixed_seconds: list[float], method_seconds: float) -> int:
    """Index (in increasing n) of the fixed count at equal time: the largest n whose time does not
    exceed the method's; 0, the smallest, when every one is slower.

    Args:
        fixed_seconds: the fixed counts' times, in increasing n. method_seconds: the method's.

    Returns:
        The index.
    """
    within = [i for i, t in enumerate(fixed_seconds) if t <= method_seconds]
    return max(within) if within else 0


def verdict(ratio: float) -> str:
    """'win' when the method's MSE is strictly below the fixed count's at equal time, else 'loss' (a
    tie at the method's own cost is no win).

    Args:
        ratio: MSE(fixed n at equal time) / MSE(method).

    Returns:
        'win' or 'loss'.
    """
    return "win" if ratio > 1 else "loss"


def ratio_of(fixed_mse: float, method_mse: float) -> float:
    """MSE(fixed) / MSE(method); 1 where both are 0, inf where only the method's is.

    Args:
        fixed_mse: the fixed count's MSE. method_mse: the method's.

    Returns:
        The ratio.
    """
    if method_mse == 0:
        return 1.0 if fixed_mse == 0 else float("inf")
    return fixed_mse / method_mse


def describe_comparison(config: dict[str, Any]) -> str:
    """Integrator keywords as text, "inner=2:16, reuse=pixels, ...".

    Args:
        config: {keyword: value}; counts are written as `show` writes them.

    Returns:
        The text.
    """
    return ", ".join(f"{k}={show(v)}" for k, v in config.items())


def show(inner: Any) -> str:
    """A count as the command line writes it: 8, '8:64,4', (64, 64) and gallery.json's [64, 64]
    as 64,64.

    Args:
        inner: a count, a count's text, or one count per level (a tuple or list).

    Returns:
        The text.
    """
    return ",".join(str(n) for n in inner) if isinstance(inner, (tuple, list)) else str(inner)


def check_comparisons(comparisons: list[Comparison]) -> None:
    """Build every integrator of the section before any renders.

    Args:
        comparisons: the comparisons.

    Raises:
        StyletraceError: a refused setting.
    """
    from styletrace.frontends import api
    for c in comparisons:
        for inner in (c.reference, fixed_inner(c, c.counts[0])):
            api.make_integrator(c.style, **{**c.integrator, **c.params, "inner": inner})
        api.make_integrator(c.style, **{**c.integrator, **c.params, **c.method})


def timed(
    scene: Any, c: Comparison, config: dict[str, Any], repeats: int
) -> tuple[np.ndarray, list[float]]:
    """The image and the seconds of `repeats` renders, after one untimed render that compiles
    the kernels.

    Args:
        scene: the loaded scene. c: the comparison. config: the render's integrator keywords.
        repeats: how many renders are timed.

    Returns:
        (the last render's image, the seconds of each timed render).
    """
    from styletrace.frontends.api import render

    def once() -> tuple[np.ndarray, float]:
        t = time.perf_counter()
        img = render(
            scene, denoise="off", style=c.style, spp=SPP, seed=SEED,
            **{**c.integrator, **c.params, **config}
        )
        return img, time.perf_counter() - t

    once()
    runs = [once() for _ in range(repeats)]
    return runs[-1][0], [t for _, t in runs]


def compare(c: Comparison, out_dir: str, size: int, repeats: int,
            log: Callable[[str], None] = print) -> tuple[dict[str, Any], dict[str, np.ndarray]]:
    """Render one comparison (see the module doc) and write its figure, `KEY.png`.

    Args:
        c: the comparison. out_dir: the gallery's folder. size: the image's side in pixels.
        repeats: timed renders per configuration. log: called with each progress line.

    Returns:
        (its gallery.json entry, its images: "reference", "fixed" (at equal time), "method").
    """
    from styletrace.frontends.api import render
    from styletrace.scene.loading import load_scene

    scene = load_scene(c.scene, size, size)
    t = time.perf_counter()
    reference = render(scene, denoise="off", style=c.style, spp=SPP, seed=SEED,
                       **{**c.integrator, **c.params, "inner": c.reference})
    ref_seconds = time.perf_counter() - t
    log(f"{c.key}: reference inner {show(c.reference)} in {ref_seconds:.1f} s")
    method_img, times = timed(scene, c, c.method, repeats)
    method = {"config": c.method, "seconds": statistics.median(times), "times": times,
              "mse": mse(method_img, reference)}
    log(f"{c.key}: method {describe_comparison(c.method)}: {method['seconds']:.3f} s, "
        f"MSE {method['mse']:.3g}")
    fixed, images = [], []
    for n in c.counts:
        img, times = timed(scene, c, {"inner": fixed_inner(c, n)}, repeats)
        fixed.append(
            {
                "n": n,
                "inner": fixed_inner(c, n),
                "seconds": statistics.median(times),
                "times": times,
                "mse": mse(img, reference),
            }
        )
        images.append(img)
        log(f"{c.key}: fixed n={n}: {fixed[-1]['seconds']:.3f} s, MSE {fixed[-1]['mse']:.3g}")
        if fixed[-1]["seconds"] > method["seconds"]:
            # every larger count is slower still (in expectation): none of them can be at equal time
            break
    i = pick([f["seconds"] for f in fixed], method["seconds"])
    ratio = ratio_of(fixed[i]["mse"], method["mse"])
    entry = {
        "key": c.key,
        "title": c.title,
        "scene": c.scene,
        "size": size,
        "spp": SPP,
        "seed": SEED,
        "style": c.style,
        "params": c.params,
        "integrator": c.integrator,
        "repeats": repeats,
        "reference": {"inner": c.reference, "seconds": ref_seconds},
        "method": method,
        "fixed": fixed,
        "equal_time": i,
        "fixed_slower": fixed[i]["seconds"] > method["seconds"],
        "ratio": ratio,
        "verdict": verdict(ratio),
        "file": f"{c.key}.png",
    }
    imgs = {"reference": reference, "fixed": images[i], "method": method_img}
    figure(entry, imgs, os.path.join(out_dir, entry["file"]))
    log(
        f"{c.key}: fixed n={fixed[i]['n']} at equal time; MSE ratio {ratio:.2f}: "
        f"{entry['verdict'].upper()}"
    )
    return entry, imgs


def prepare_comparisons(
    comparisons: list[Comparison], quick_mode: bool = False
) -> list[Comparison]:
    """The comparisons as they will render, every integrator built once so that refused settings
    fail before anything renders.

    Args:
        comparisons: the section's comparisons. quick_mode: make them `quick`.

    Returns:
        The comparisons to render.

    Raises:
        StyletraceError: a refused setting.
    """
    comparisons = [quick(c) for c in comparisons] if quick_mode else list(comparisons)
    check_comparisons(comparisons)
    return comparisons


def headline(e: dict[str, Any]) -> str:
    """The verdict line of an entry: "win: ..." or "LOSS: ...", with the ratio and the fixed n.

    Args:
        e: a comparison's gallery.json entry.

    Returns:
        The line.
    """
    f = e["fixed"][e["equal_time"]]
    if e["verdict"] == "win":
        return f"win: {e['ratio']:.2f}x lower MSE than fixed n={f['n']} at equal time"
    return f"LOSS: the method's MSE is {1 / e['ratio']:.2f}x that of fixed n={f['n']} at equal time"


def labels(e: dict[str, Any]) -> list[tuple[str, str]]:
    """(what, numbers) of the three panels: reference, fixed n at equal time, method.

    Args:
        e: a comparison's gallery.json entry.

    Returns:
        Three (title, times and errors) pairs.
    """
    f, m = e["fixed"][e["equal_time"]], e["method"]
    note = " (slower than the method: no fixed count is faster)" if e["fixed_slower"] else ""
    return [
        (f"reference, inner {show(e['reference']['inner'])}", f"{e['reference']['seconds']:.1f} s"),
        (
            f"fixed n={f['n']} (inner {show(f['inner'])}), equal time{note}",
            f"{f['seconds']:.3f} s, MSE {f['mse']:.2e}",
        ),
        (f"method: {describe_comparison(m['config'])}",
         f"{m['seconds']:.3f} s, MSE {m['mse']:.2e}"),
    ]


def figure(e: dict[str, Any], images: dict[str, np.ndarray], path: str) -> None:
    """reference | fixed n at equal time | method, tone-mapped as the gallery's PNGs, written
    atomically.

    Args:
        e: the comparison's entry. images: its "reference", "fixed" and "method" images.
        path: the PNG's path.
    """
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from styletrace.images import srgb8, write_bytes_atomically
    fig, axes = plt.subplots(1, 3, figsize=(9, 4.3))
    for ax, img, (what, numbers) in zip(
        axes, (images["reference"], images["fixed"], images["method"]), labels(e)
    ):
        ax.imshow(srgb8(img), interpolation="nearest")
        ax.set_title(textwrap.fill(what, 38) + "\n" + numbers, fontsize=8)
        ax.axis("off")
    fig.suptitle(f"{e['title']}\n{headline(e)}", fontsize=10, fontweight="bold",
                 color="#1a7f1a" if e["verdict"] == "win" else "#b00000")
    fig.tight_layout(rect=(0, 0, 1, 0.87))  # the top for the title and the verdict
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=100)
    write_bytes_atomically(buf.getvalue(), path)
    plt.close(fig)


INTRO = (
    "Each comparison renders at 1 camera sample per pixel with one seed, against a reference of "
    "the same seed (the same camera rays: the error is the stylized estimate's); times are the "
    "median of {repeats} timed render(s) after one that compiles the kernels. The fixed count at "
    "equal time is the largest n whose render is not slower than the method's (the smallest n when "
    "all are slower). Ratio: the fixed count's MSE over the method's; at 1 or below the method "
    "loses at equal time, whatever it gains at equal inner counts. Protocol: the docstring of "
    "styletrace/frontends/equal_time.py."
)


def rows(e: dict[str, Any]) -> list[tuple[str, str, str, str]]:
    """The rows of an entry's table, (render, inner, seconds, MSE): reference, fixed n, method.

    Args:
        e: a comparison's gallery.json entry.

    Returns:
        Three rows of text cells.
    """
    f, m = e["fixed"][e["equal_time"]], e["method"]
    return [
        ("reference", show(e["reference"]["inner"]), f"{e['reference']['seconds']:.1f}", ""),
        (
            f"fixed n={f['n']} (equal time)",
            show(f["inner"]),
            f"{f['seconds']:.3f}",
            f"{f['mse']:.3e}",
        ),
        ("method", describe_comparison(m["config"]), f"{m['seconds']:.3f}", f"{m['mse']:.3e}"),
    ]


def sheet_md(entries: list[dict[str, Any]]) -> list[str]:
    """The section's part of the Markdown contact sheet.

    Args:
        entries: the comparisons' gallery.json entries.

    Returns:
        Its lines ([] for no entries).
    """
    if not entries:
        return []
    e0 = entries[0]
    md = [
        f"## Equal time: a method against the fixed counts ({e0['scene']}, "
        f"{e0['size']}x{e0['size']})",
        "",
        INTRO.format(repeats=e0["repeats"]),
        "",
        "| comparison | method | fixed n at equal time | MSE ratio | verdict |",
        "|---|---|---:|---:|---|",
    ]
    md += [
        f"| {e['title']} | `{describe_comparison(e['method']['config'])}` | "
        f"{e['fixed'][e['equal_time']]['n']} | {e['ratio']:.2f} | "
        f"{'win' if e['verdict'] == 'win' else '**LOSS**'} |"
        for e in entries
    ]
    for e in entries:
        md += ["", f"### {e['title']}: {'win' if e['verdict'] == 'win' else '**LOSS**'}", "",
               f"`{e['style']}` "
               f"{describe_comparison({**e['params'], **e['integrator']})}".rstrip(),
               "",
               "| render | inner | s | MSE |", "|---|---|---:|---:|",
               *(f"| {a} | {b} | {c} | {d} |" for a, b, c, d in rows(e)), "",
               f"{headline(e)}.", "", f"![{e['title']}]({e['file']})"]
    return md + [""]


def sheet_html(entries: list[dict[str, Any]]) -> list[str]:
    """The section's part of the HTML contact sheet.

    Args:
        entries: the comparisons' gallery.json entries.

    Returns:
        Its lines ([] for no entries).
    """
    if not entries:
        return []
    esc = html.escape
    e0 = entries[0]

    def mark(e):
        return ("<strong style='color:#1a7f1a'>win</strong>" if e["verdict"] == "win"
                else "<strong style='color:#b00000;font-size:1.2em'>LOSS</strong>")

    h = [
        f"<h2>Equal time: a method against the fixed counts ({esc(e0['scene'])}, "
        f"{e0['size']}x{e0['size']})</h2>",
        f"<p>{esc(INTRO.format(repeats=e0['repeats']))}</p>",
        "<table border='1' cellpadding='4' style='border-collapse:collapse'>"
        "<tr><th>comparison<th>method<th>fixed n at equal time<th>MSE ratio<th>verdict</tr>",
    ]
    h += [
        f"<tr><td>{esc(e['title'])}<td><code>{esc(describe_comparison(e['method']['config']))}</code>"
        f"<td>{e['fixed'][e['equal_time']]['n']}<td>{e['ratio']:.2f}<td>{mark(e)}</tr>"
        for e in entries
    ]
    h += ["</table>"]
    for e in entries:
        h += [
            f"<h3>{esc(e['title'])}: {mark(e)}</h3>",
            f"<p><code>{esc(e['style'])}</code> "
            f"{esc(describe_comparison({**e['params'], **e['integrator']}))}</p>",
            "<table border='1' cellpadding='4' style='border-collapse:collapse'>"
            "<tr><th>render<th>inner<th>s<th>MSE</tr>"
            + "".join(f"<tr><td>{esc(a)}<td>{esc(b)}<td>{c}<td>{d}</tr>" for a, b, c, d in rows(e))
            + "</table>",
            f"<p>{esc(headline(e))}.</p>",
            f"<img src='{e['file']}' style='width:900px;image-rendering:auto'>",
        ]
    return h
