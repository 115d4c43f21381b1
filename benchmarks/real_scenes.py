"""Every style at its defaults on a panel of public scenes: the BENCHMARKS.md section "Real scenes
at defaults" and docs/real_scenes.png.

    .venv/bin/python benchmarks/real_scenes.py [--panel DIR] [--size 512] [--scenes a,b]
        [--styles a,b] [--no-write]

The panel (benchmarks/panel.json: each scene's source, licence, category and split) is read from DIR
(default $STYLETRACE_PANEL, else benchmarks/.cache/panel): DIR/NAME/scene.xml with its assets. Each
scene keeps its own filter, integrator, sensor and sampler count; only the film is resized so that
its longer side is --size.

Per scene and style, at every default (`--denoise auto`, docs/look.md), one process, 2 seeds:
- time: the wall time of the seed-0 render, loading excluded, kernels compiled (a warm-up render at
  32 px first);
- cost: that time over the identity style's at its defaults on the same scene and size;
- noise: PSNR in sRGB between the two seeds (`measures.noise_psnr`);
- tone: the rank correlation of the blurred luminance with the identity style's
  (`measures.tone_correlation`; the identity render is denoised at 4x the scene's sample count, a
  converged stand-in);
- clipped and crushed pixel shares, and the firefly share for styles without a screen pattern. The
  goals (issue 29) are checked on the held-out half of the panel: the defaults were chosen without
  it.
"""
from __future__ import annotations

import argparse
import json
import os
import sys
import time
from pathlib import Path

import numpy as np
from _report import image_grid, machine_description, write_section

import styletrace
from styletrace import measures
from styletrace.scene.loading import load_scene, scene_spp
from styletrace.styles import style_names

os.environ.setdefault("STYLETRACE_DENOISE", "auto")
styletrace.init()

HERE = Path(__file__).resolve().parent
MANIFEST = HERE / "panel.json"
DEFAULT_PANEL = HERE / ".cache" / "panel"
SCREEN = ("hatching", "halftone")  # styles with a screen pattern: no firefly share
GOALS = {
    "psnr": 30.0,
    "tone": 0.7,
    "clipped": 0.10,
    "crushed": 0.10,
    "fireflies": 0.001,
    "cost": 3.0,
}


def film_size(path: Path, longest: int) -> tuple[int, int]:
    """The scene's own film aspect with its longer side `longest`."""
    size = load_scene(str(path)).sensors()[0].film().size()
    w, h = int(size[0]), int(size[1])
    scale = longest / max(w, h)
    return max(1, round(w * scale)), max(1, round(h * scale))


def render(path: Path, style: str, size, seed: int, **kw) -> tuple[np.ndarray, float]:
    t = time.perf_counter()
    with __import__("warnings").catch_warnings():
        __import__("warnings").simplefilter("ignore")
        img = styletrace.render(
            str(path), style=style, width=size[0], height=size[1], seed=seed, **kw
        )
    return np.asarray(img, dtype=np.float32)[..., :3], time.perf_counter() - t


def measure(path: Path, styles: list[str], longest: int, fresh: bool = False) -> dict:
    """The scene's rows and thumbnails, kept in benchmarks/.cache/real_scenes so that a stopped
    run resumes."""
    cache = HERE / ".cache" / "real_scenes" / f"{path.parent.name}-{longest}.pkl"
    import pickle
    if cache.exists() and not fresh:
        kept = pickle.loads(cache.read_bytes())
        if all(s in kept["rows"] for s in styles):
            kept["rows"] = {s: kept["rows"][s] for s in styles}
            kept["thumbs"] = {s: kept["thumbs"][s] for s in styles}
            return kept
    out = _measure(path, styles, longest)
    cache.parent.mkdir(parents=True, exist_ok=True)
    cache.write_bytes(pickle.dumps(out))
    return out


def _measure(path: Path, styles: list[str], longest: int) -> dict:
    size = film_size(path, longest)
    spp = scene_spp(load_scene(str(path)))
    render(path, "identity", (32, 32), 0)  # compile what every style shares
    reference, _ = render(path, "identity", size, 7, spp=4 * spp)
    rows, thumbs = {}, {}
    for style in styles:
        render(path, style, (32, 32), 0)  # this style's kernels compiled
        a, seconds = render(path, style, size, 0)
        b, _ = render(path, style, size, 1)
        rows[style] = {"time": seconds, "psnr": measures.noise_psnr(a, b),
                       "tone": measures.tone_correlation(a, reference, 8),
                       "clipped": measures.clipped_share(a), "crushed": measures.crushed_share(a),
                       "fireflies": None if style in SCREEN else measures.firefly_share(a)}
        thumbs[style] = a
        print(
            f"  {style:>10}: {seconds:6.1f} s  PSNR {rows[style]['psnr']:5.1f}  tone "
            f"{rows[style]['tone']:.2f}  "
            f"clipped {rows[style]['clipped']:.3f}  crushed {rows[style]['crushed']:.3f}  "
            f"fireflies "
            f"{rows[style]['fireflies'] if rows[style]['fireflies'] is not None else '-'}",
            flush=True,
        )
    base = rows.get("identity", {}).get("time")
    for row in rows.values():
        row["cost"] = row["time"] / base if base else None
    return {"size": size, "spp": spp, "rows": rows, "thumbs": thumbs}


def single_image_measures(results: dict) -> None:
    """Clipping, crushing and fireflies from each row's seed-0 image (kept), so that a change of
    those measures needs no new render."""
    for res in results.values():
        for style, row in res["rows"].items():
            img = res["thumbs"][style]
            row.update(clipped=measures.clipped_share(img), crushed=measures.crushed_share(img),
                       fireflies=None if style in SCREEN else measures.firefly_share(img))


def misses(row: dict, style: str) -> list[str]:
    """The goals a row misses."""
    out = []
    if row["psnr"] < GOALS["psnr"]:
        out.append("psnr")
    if row["tone"] < GOALS["tone"]:
        out.append("tone")
    if row["clipped"] > GOALS["clipped"]:
        out.append("clipped")
    if row["crushed"] > GOALS["crushed"]:
        out.append("crushed")
    if row["fireflies"] is not None and row["fireflies"] > GOALS["fireflies"]:
        out.append("fireflies")
    if style != "identity" and row["cost"] is not None and row["cost"] > GOALS["cost"]:
        out.append("cost")
    return out


def table(results: dict, panel: list[dict], held_out: bool) -> str:
    lines = [
        "| scene | style | time (s) | cost vs identity | PSNR (dB) | tone | clipped | crushed | "
        "fireflies | "
        "goals missed |",
        "|---|---|---|---|---|---|---|---|---|---|",
    ]
    for entry in panel:
        if entry["name"] not in results or entry["held_out"] != held_out:
            continue
        res = results[entry["name"]]
        for style, row in res["rows"].items():
            ff = "-" if row["fireflies"] is None else f"{100 * row['fireflies']:.2f}%"
            cost = "-" if row["cost"] is None else f"{row['cost']:.2f}x"
            lines.append(
                f"| {entry['name']} | {style} | {row['time']:.1f} | {cost} | {row['psnr']:.1f} | "
                f"{row['tone']:.2f} | {100 * row['clipped']:.1f}% | {100 * row['crushed']:.1f}% | "
                f"{ff} | "
                f"{', '.join(misses(row, style)) or 'none'} |"
            )
    return "\n".join(lines)


def contact_sheet(results: dict, panel: list[dict], path: Path) -> None:
    rows = []
    for entry in panel:
        res = results.get(entry["name"])
        if res is None:
            continue
        cells = [
            (f"{style} {res['rows'][style]['time']:.0f} s", img)
            for style, img in res["thumbs"].items()
        ]
        split = "held out" if entry["held_out"] else "tuning"
        # the row's name over its first
        cells[0] = (f"{entry['name']} ({split})\n{cells[0][0]}", cells[0][1])
        rows.append((entry["name"], cells))
    columns = max(len(cells) for _, cells in rows)
    image_grid(rows, str(path), row_height=1.9, fontsize=6, width=1.45 * columns)


def main(argv: list[str]) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--panel", default=os.environ.get("STYLETRACE_PANEL", str(DEFAULT_PANEL)))
    ap.add_argument("--size", type=int, default=512)
    ap.add_argument("--scenes", default="")
    ap.add_argument("--styles", default="")
    ap.add_argument("--no-write", action="store_true")
    ap.add_argument("--fresh", action="store_true", help="measure again what the cache holds")
    args = ap.parse_args(argv)
    panel = json.loads(MANIFEST.read_text())["scenes"]
    chosen = [e for e in panel if not args.scenes or e["name"] in args.scenes.split(",")]
    styles = (
        args.styles.split(",")
        if args.styles
        else ["identity"] + [s for s in style_names() if s != "identity"]
    )
    missing = [
        e["name"] for e in chosen if not (Path(args.panel) / e["name"] / "scene.xml").exists()
    ]
    if missing:
        print(
            f"real_scenes: the panel's scenes are not in {args.panel}: {', '.join(missing)} "
            f"(benchmarks/panel.json "
            f"names their sources; set --panel or $STYLETRACE_PANEL)",
            file=sys.stderr,
        )
        return 2
    results = {}
    for entry in chosen:
        print(f"{entry['name']} ({'held out' if entry['held_out'] else 'tuning'})", flush=True)
        results[entry["name"]] = measure(
            Path(args.panel) / entry["name"] / "scene.xml", styles, args.size, args.fresh
        )
    single_image_measures(results)
    if args.no_write:
        return 0
    contact_sheet(results, chosen, HERE.parent / "docs" / "real_scenes.png")
    held = [e for e in chosen if e["held_out"]]
    misses_held = sum(
        bool(misses(row, style)) for e in held for style, row in results[e["name"]]["rows"].items()
    )
    rows_held = sum(len(results[e["name"]]["rows"]) for e in held)
    scenes_line = "; ".join(
        f"{e['name']} ({results[e['name']]['size'][0]}x{results[e['name']]['size'][1]}, "
        f"{results[e['name']]['spp']} spp)"
        for e in chosen
    )
    body = f"""## Real scenes at defaults

Written by `python benchmarks/real_scenes.py --size {args.size}` on {machine_description()}.

Every style with nothing but `--style` (denoise auto, the firefly control, the scene's sample \
count spent on
children: docs/look.md), on the public scenes of benchmarks/panel.json at the longer side \
{args.size}, each with its
own filter, integrator, sensor and sample count: {scenes_line}. Cost is the style's wall time over \
the identity
style's at its defaults, the same scene and size. Tone is the rank correlation with the identity \
render's blurred
luminance. Goals (issue 29), on the held-out half: PSNR >= {GOALS['psnr']:g} dB, tone >= \
{GOALS['tone']:g},
clipped and crushed <= {100 * GOALS['clipped']:g}%, fireflies <= {100 * GOALS['fireflies']:g}% \
(styles without a
screen pattern), cost <= {GOALS['cost']:g}x. The defaults were chosen on the built-in scenes and \
the tuning half;
the held-out half was rendered for the first time here. Held out: {rows_held - misses_held} of \
{rows_held} rows meet
every goal.

### Held out

{table(results, chosen, True)}

### Tuning half

{table(results, chosen, False)}

Contact sheet: docs/real_scenes.png.
"""
    write_section("real_scenes", body)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
