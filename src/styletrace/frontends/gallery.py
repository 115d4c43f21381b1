"""`styletrace gallery`: the paper's result setups (supplement S5, Figs. 7-12) on the
built-in dragon.

Each setup renders the dragon with one style at several inner sample counts n; setups with a
brute-force reference (the colour map at 1024 samples per style evaluation, cel at 4096, as in
the supplement) also get each render's mean squared error against it, plotted against n. The
results land in one folder: PNGs, `mse.png`, `gallery.json` and the contact sheet `index.html` /
`index.md`. The equal-time section (`EQUAL_TIME`, `equal_time.py`) follows; `--only equal_time`
runs it alone, `--skip equal_time` leaves it out. Quick mode (`--quick`) finishes in well under
a minute; CI runs it. Design: docs/design/equal_time.md.
"""
from __future__ import annotations

import html
import io
import json
import os
import time
from dataclasses import dataclass, field
from typing import Any, Callable

import numpy as np

from styletrace.frontends import equal_time
from styletrace.frontends.equal_time import Comparison
from styletrace.images import mse  # noqa: F401  (the gallery's error measure; also used by its tests)


@dataclass
class Setup:
    key: str
    title: str            # what it shows, with the paper's figure
    style: str
    counts: tuple[int, ...]
    reference: int = 0    # inner samples of the brute-force reference (0: none)
    reference_note: str = ""
    params: dict[str, Any] = field(default_factory=dict)
    integrator: dict[str, Any] = field(default_factory=dict)
    scene: str = "dragon"
    estimator: str = "direct"


#: feature lines (docs/lines.md): on, with a gradient from deep blue at the feet to warm red at
#: the top
LINES = {"lines": True, "line_width": 1.5}
LINE_GRADIENT = "0.05,0.1,0.5;0.8,0.15,0.05;0;1"

SETUPS = [
    Setup(
        "color_map",
        "Colour mapping, direct estimator (Fig. 7)",
        "color_map",
        (1, 4, 16, 64),
        reference=1024,
        params={"gradient": "dusk"},
    ),
    Setup(
        "acp",
        "ACP baseline: colour map per path sample (Fig. 7, Doi et al. 2021)",
        "acp",
        (1, 4, 16, 64),
        params={"gradient": "dusk"},
    ),
    Setup(
        "cel",
        "GI cel shading, direct estimator (Fig. 8)",
        "cel",
        (1, 4, 16, 64),
        reference=4096,
        params={"thresholds": "0.3", "levels": "0.25,0.85"},
    ),
    Setup(
        "saturation",
        "Recursive saturation, first 2 hits, 8 samples per evaluation, w = 0.5 (Fig. 9)",
        "saturation",
        (8,),
        params={"w": 0.5},
        integrator={"stylize": "first_n_hits", "stylize_depth": 2},
    ),
    Setup(
        "gamma_direct", "Gamma 1/2.2, direct application (biased) (Fig. 10)", "gamma", (1, 4, 16)
    ),
    Setup(
        "gamma_series",
        "Gamma 1/2.2, unbiased power series: iterative prefix sum, pilot of n (Fig. 10)",
        "gamma",
        (4, 16),
        estimator="series",
    ),
    Setup(
        "gamma_roulette",
        "Gamma 1/2.2, unbiased power series: Russian roulette prefix sum (Fig. 10)",
        "gamma",
        (4, 16),
        estimator="series_recursive",
    ),
    Setup(
        "contrast",
        "Contrast c(I - p) + p, affine, unbiased (Fig. 10)",
        "contrast",
        (1, 8),
        params={"c": 1.6, "pivot": 0.3},
        estimator="affine",
    ),
    Setup(
        "sepia",
        "Sepia: affine colour map over [0, inf), unbiased (Fig. 10)",
        "sepia",
        (1, 8),
        estimator="affine",
    ),
    Setup(
        "combined",
        "Sepia after contrast as one style, combined gu-estimator, 1 sample per operand (Fig. 10)",
        "contrast+sepia",
        (1, 8),
        params={"contrast.c": 1.6, "contrast.pivot": 0.3},
        estimator="combined",
    ),
    Setup(
        "tie_dye",
        "Tie-dye via its degree-20 Chebyshev fit, U-statistic, unbiased for the fit (Fig. 11)",
        "tie_dye",
        (20, 64),
        estimator="ustat",
    ),
    Setup(
        "gooch",
        "Gooch shading, closed form, 0 samples (Fig. 12)",
        "gooch",
        (0,),
        params={"light_dir": "0.2,1,0.3"},
    ),
    Setup(
        "xtoon",
        "X-Toon, closed form, 0 samples (Fig. 12)",
        "xtoon",
        (0,),
        params={"light_dir": "0.2,1,0.3"},
    ),
    Setup(
        "hatching",
        "Cross-hatching (Fig. 12)",
        "hatching",
        (16,),
        params={"spacing": 0.05, "u_min": 0.05, "u_max": 0.45},
    ),
    Setup(
        "halftone",
        "Half-tone (Fig. 12)",
        "halftone",
        (16,),
        params={"spacing": 0.05, "u_min": 0.05, "u_max": 0.6},
    ),
    Setup(
        "mixed",
        "Per object: cel dragon, hatched floor, PBR glass; seen through the glass too",
        "identity",
        (1,),
        integrator={"stylize": "first_object_hit"},
        scene="mixed",
    ),
    Setup(
        "lines",
        "Colour map with physically based feature lines, colour over world y (Fig. 12 middle, West "
        "2021)",
        "color_map",
        (8,),
        params={"gradient": "dusk"},
        integrator=dict(LINES, line_gradient=LINE_GRADIENT),
    ),
    Setup(
        "lines_mirror",
        "Feature lines seen in a mirror and through a glass sphere (line_depth 3)",
        "identity",
        (1,),
        integrator=dict(LINES, line_gradient=LINE_GRADIENT, line_depth=3),
        scene="lines",
    ),
]

#: The equal-time section: each method against the fixed counts at equal time (protocol:
#: equal_time.py). Edit the `method` configurations here; each is any set of integrator keywords
#: (inner, reuse, reuse_k, ...).
POOLED = {"reuse": "pixels", "reuse_mis": "pairwise"}
EQUAL_TIME = [
    Comparison(
        "equal_time_cel",
        "GI cel shading, first hit: reuse with a refinement round against fixed n",
        "cel",
        method={"inner": "2:16", **POOLED, "reuse_radius": 3, "reuse_k": 48},
        reference=4096,
    ),
    Comparison(
        "equal_time_hatching",
        "Cross-hatching, first hit: reuse with a refinement round against fixed n",
        "hatching",
        method={"inner": "2:32", **POOLED, "reuse_radius": 3, "reuse_k": 48},
        reference=4096,
    ),
    Comparison(
        "equal_time_color_map",
        "Colour mapping, first hit: reuse against fixed n",
        "color_map",
        method={"inner": 4, **POOLED, "reuse_k": 24},
        reference=1024,
    ),
    # the fixed curve n,1: the cheapest split of the two levels' counts at equal time
    # (BENCHMARKS.md equal_time)
    Comparison(
        "equal_time_saturation",
        "Saturation, first 2 hits: reuse at the first hits against fixed n,1",
        "saturation",
        method={"inner": "2,1", **POOLED, "reuse_radius": 3, "reuse_k": 48},
        reference=(256, 16),
        integrator={"stylize": "first_n_hits", "stylize_depth": 2},
        counts=(2, 4, 8, 16, 32, 64),
        below=(1,),
    ),
]
#: the --only / --skip key of the whole equal-time section
EQUAL_TIME_SECTION = "equal_time"


@dataclass
class Options:
    size: int = 192
    spp: int = 8
    reference_spp: int = 4
    quick: bool = False
    equal_time_size: int = 128   # the equal-time section's image size (1 spp, equal_time.py)
    equal_time_repeats: int = 3  # timed renders per configuration; the median counts


QUICK = Options(
    size=48, spp=2, reference_spp=2, quick=True, equal_time_size=32, equal_time_repeats=1
)


def keys() -> list[str]:
    """Everything --only and --skip accept: the setups, the comparisons and the
    equal-time section."""
    return [s.key for s in SETUPS] + [c.key for c in EQUAL_TIME] + [EQUAL_TIME_SECTION]


def select_setups(only: list[str] | None = None,
           skip: list[str] | None = None) -> tuple[list[Setup], list[Comparison]]:
    """The setups and comparisons to run.

    Args:
        only: the keys to run (None: all); `equal_time` names every comparison.
        skip: the keys to leave out (None: none).

    Returns:
        (setups, comparisons).

    Raises:
        ValueError: an unknown key (the message names the keys there are).
    """
    unknown = sorted(set(only or ()).union(skip or ()) - set(keys()))
    if unknown:
        raise ValueError(
            f"unknown gallery setup(s) {', '.join(unknown)}: available are {', '.join(keys())}"
        )

    def chosen(names: set[str]) -> bool:  # names: the key and the section it belongs to
        return (only is None or bool(names & set(only))) and not names & set(skip or ())
    return ([s for s in SETUPS if chosen({s.key})],
            [c for c in EQUAL_TIME if chosen({c.key, EQUAL_TIME_SECTION})])


def _quick(setup: Setup) -> Setup:
    counts = tuple(sorted({min(n, 20 if setup.estimator == "ustat" else 4) for n in setup.counts}))
    ref = min(setup.reference, 64) if setup.reference else 0
    note = f"quick mode: {ref} samples per evaluation instead of {setup.reference}" if ref else ""
    return Setup(**{**setup.__dict__, "counts": counts, "reference": ref, "reference_note": note})


def write_png(image: np.ndarray, path: str) -> None:
    """Write an image (`images.write_image`, atomically; a .png is sRGB).

    Args:
        image: H x W x 3, linear. path: the file.
    """
    from styletrace.images import write_image
    write_image(image, path)


def run_gallery(out_dir: str, options: Options = Options(), only: list[str] | None = None,
        log: Callable[[str], None] = print, skip: list[str] | None = None) -> dict[str, Any]:
    """Render the chosen setups and comparisons into `out_dir`, saving after each comparison.

    Args:
        out_dir: the folder (made here). options: sizes and counts (`Options`, `QUICK`).
        only, skip: as `select_setups`'s. log: called with each progress line.

    Returns:
        The results as gallery.json holds them: options, setups, equal_time, seconds.

    Raises:
        ValueError: an unknown key. StyletraceError: a refused setting, before any render.
    """
    from styletrace.frontends.api import render
    from styletrace.scene.loading import load_scene

    os.makedirs(out_dir, exist_ok=True)
    setups, comparisons = select_setups(only, skip)
    results: dict[str, Any] = {"options": options.__dict__, "setups": [], "equal_time": []}
    t_all = time.perf_counter()
    # refused settings stop it before any render
    comparisons = equal_time.prepare_comparisons(comparisons, options.quick)
    for setup in setups:
        if options.quick:
            setup = _quick(setup)
        scene = load_scene(setup.scene, options.size, options.size)
        entry: dict[str, Any] = {
            "key": setup.key,
            "title": setup.title,
            "style": setup.style,
            "estimator": setup.estimator,
            "params": setup.params,
            "integrator": setup.integrator,
            "renders": [],
        }
        reference = None
        if setup.reference:
            t = time.perf_counter()
            reference = render(
                scene,
                denoise="off",
                style=setup.style,
                inner=setup.reference,
                spp=options.reference_spp,
                seed=10_000,
                **setup.integrator,
                **setup.params,
            )
            name = f"{setup.key}_reference.png"
            write_png(reference, os.path.join(out_dir, name))
            entry["reference"] = {
                "file": name,
                "inner": setup.reference,
                "spp": options.reference_spp,
                "seconds": time.perf_counter() - t,
                "note": setup.reference_note,
            }
            log(
                f"{setup.key}: reference n={setup.reference} in "
                f"{entry['reference']['seconds']:.1f} s"
            )
        for n in setup.counts:
            t = time.perf_counter()
            inner = None if n == 0 else n
            img = render(
                scene,
                denoise="off",
                style=setup.style,
                inner=inner,
                estimator=setup.estimator if n else "direct",
                spp=options.spp,
                seed=n,
                **setup.integrator,
                **setup.params,
            )
            secs = time.perf_counter() - t
            name = f"{setup.key}_n{n}.png"
            write_png(img, os.path.join(out_dir, name))
            r = {"n": n, "file": name, "seconds": secs, "spp": options.spp}
            if reference is not None:
                r["mse"] = mse(img, reference)
            entry["renders"].append(r)
            log(
                f"{setup.key}: n={n} in {secs:.1f} s"
                + (f", MSE {r['mse']:.3g}" if "mse" in r else "")
            )
        results["setups"].append(entry)
    plot_mse(results, os.path.join(out_dir, "mse.png"))
    save(results, out_dir, t_all)
    # saved after each: an error or Ctrl-C in a later one loses none of the finished
    for c in comparisons:
        results["equal_time"].append(equal_time.compare(c, out_dir, options.equal_time_size,
                                                        options.equal_time_repeats, log)[0])
        save(results, out_dir, t_all)
    return results


def save(results: dict[str, Any], out_dir: str, started: float) -> None:
    """gallery.json and the contact sheets of what has rendered so far.

    Args:
        results: the results so far. out_dir: the folder. started: `time.perf_counter()` at start.
    """
    results["seconds"] = time.perf_counter() - started
    write_text(os.path.join(out_dir, "gallery.json"), json.dumps(results, indent=1))
    write_sheets(results, out_dir)


def plot_mse(results: dict[str, Any], path: str) -> None:
    """Plot each setup's MSE against n (log-log) into a PNG, written atomically.

    Args:
        results: the results (the setups with a reference are plotted). path: the PNG's path.
    """
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(5, 3.6), dpi=120)
    for e in results["setups"]:
        pts = [(r["n"], r["mse"]) for r in e["renders"] if "mse" in r]
        if pts:
            ns, mses = zip(*pts)
            ax.loglog(ns, mses, "o-", label=f"{e['style']} (ref n={e['reference']['inner']})")
    ax.set_xlabel("inner samples per style evaluation n")
    ax.set_ylabel("MSE against the reference")
    ax.set_title("Direct estimator: error vs n")
    ax.grid(True, which="both", alpha=0.3)
    if ax.lines:
        ax.legend(fontsize=8)
    fig.tight_layout()
    buf = io.BytesIO()
    fig.savefig(buf, format="png")
    from styletrace.images import write_bytes_atomically
    write_bytes_atomically(buf.getvalue(), path)
    plt.close(fig)


def write_sheets(results: dict[str, Any], out_dir: str) -> None:
    """Write the contact sheets index.md and index.html.

    Args:
        results: the results so far. out_dir: the folder.
    """
    o = results["options"]
    md = [
        "# styletrace gallery",
        "",
        f"Dragon scene, {o['size']}x{o['size']}, {o['spp']} camera samples per pixel; total "
        f"{results['seconds']:.0f} s. `mse.png` plots the error of each render against its "
        "reference.",
        "",
        "![MSE vs n](mse.png)",
        "",
    ]
    h = [
        "<!doctype html><meta charset='utf-8'><title>styletrace gallery</title>",
        "<style>body{font-family:sans-serif;margin:2em}figure{display:inline-block;margin:4px;text-align:center}img{image-rendering:pixelated;width:192px}figcaption{font-size:12px}</style>",
        "<h1>styletrace gallery</h1>",
        f"<p>Dragon scene, {o['size']}x{o['size']}, {o['spp']} spp; total {results['seconds']:.0f} "
        "s.</p>",
        "<img src='mse.png' style='width:480px'>",
    ]
    for e in results["setups"]:
        params = ", ".join(f"{k}={v}" for k, v in {**e["params"], **e["integrator"],
                                                   "estimator": e["estimator"]}.items())
        md += [f"## {e['title']}", "", f"`{e['style']}` {params}", ""]
        h += [
            f"<h2>{html.escape(e['title'])}</h2><p><code>{html.escape(e['style'])}</code> "
            f"{html.escape(params)}</p>"
        ]
        cells = []
        for r in e["renders"]:
            cap = f"n={r['n']}, {r['seconds']:.1f} s" + (
                f", MSE {r['mse']:.2e}" if "mse" in r else ""
            )
            cells.append((r["file"], cap))
        if "reference" in e:
            ref = e["reference"]
            cells.append(
                (
                    ref["file"],
                    f"reference n={ref['inner']}" + (f" ({ref['note']})" if ref["note"] else ""),
                )
            )
        md += [" | ".join(c for _, c in cells), " | ".join("---" for _ in cells),
               " | ".join(f"![{c}]({f})" for f, c in cells), ""]
        h += [
            "<div>"
            + "".join(
                f"<figure><img src='{f}'><figcaption>{html.escape(c)}</figcaption></figure>"
                for f, c in cells
            )
            + "</div>"
        ]
    md += equal_time.sheet_md(results.get("equal_time", []))
    h += equal_time.sheet_html(results.get("equal_time", []))
    write_text(os.path.join(out_dir, "index.md"), "\n".join(md) + "\n")
    write_text(os.path.join(out_dir, "index.html"), "\n".join(h) + "\n")


def write_text(path: str, text: str) -> None:
    """Write a text file atomically (UTF-8).

    Args:
        path: the file. text: its content.
    """
    from styletrace.images import write_bytes_atomically
    write_bytes_atomically(text.encode(), path)
