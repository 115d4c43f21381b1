"""Accuracy against Cycles (issue 46, point 4): styletrace's identity and cel styles, and Cycles,
each against its own converged image, on three Blender scenes (`_accuracy_scenes`: `window`, a
room lit through a window; `lamps`, a room lit by 20 small lamps; `still_life`, glossy metal and
glass). Run with the Blender venv (bpy as a module), on an otherwise idle machine:

    .venv-blender/bin/python benchmarks/accuracy.py [--size 128] [--scenes window,lamps,still_life]
        [--quick] [--no-write]

Protocol, the same for both renderers (scenes at --size square, Cycles on the CPU with 2 threads):
- Error of an image d: mean over pixels and channels of (d - r1)(d - r2), where r1 and r2 are two
  converged references of the same renderer and style with their own seeds (REF_SEEDS), none
  shared with d. Their noise is independent of d's and of each other's, so the product's
  expectation is the squared error of d against the references' expectation, the converged
  image: the references' own noise cancels in expectation, and shows only in the estimate's
  standard error (from the pixels' spread, given as +-). Every image is clipped to [0, PEAK]
  (linear radiance, PEAK = 1: what the Standard view transform displays) before the product, so
  that a visible lamp or a firefly weighs at most a white pixel. PSNR = 10 log10(PEAK^2 / error).
- Converged images (`Plan`: 1024 samples per pixel for Cycles, 4096 for styletrace identity, 16
  camera samples x 256 children for cel): styletrace identity and Cycles without denoising,
  clamping or adaptive sampling (Cycles: tests/blender/scenes.py's `cycles`, a one-pixel box filter
  as styletrace's film, 64 bounces); styletrace cel by direct application at that large inner count
  (as benchmarks/denoise.py's pixel reference: the look g(E[L]) that cel converges to, up to the
  smearing of band edges by a mean of 256 children, which the two references share and the
  estimate does not cancel). On these interiors it has not converged: the children of a full
  path are so noisy against cel's narrow auto bands (window: thresholds 0.089 and 0.152) that the
  mean of 256 still flips bands from pixel to pixel (a speckled image with no flat band), so
  cel's goal is judged against the defaults at Samples 1024 (`Plan.ref_limit`) as well. The noise
  left in one reference: mean((r1 - r2)^2) / 2, as a PSNR
  ("one reference" rows). Cycles' references are as noisy as its 1024-sample render: the estimate
  needs them independent, not clean, and its standard error says what their noise costs.
- Raw error per sample: no denoising, `Plan.raw_spp` (64 and 1024) samples per pixel
  (styletrace: its Samples with Denoise Off, every other setting the add-on's default, so cel
  splits them into camera samples x the style's children as the add-on does, and its error
  includes the bias of that mean at the band edges; Cycles: `cycles`), seed RAW_SEED. Time: the
  F12 call's wall time (render and EXR write; an untimed render of the same settings at 64 samples
  first compiles the kernels).
- Equal time: styletrace's F12 at the add-on's defaults (Samples, Denoise, firefly control,
  sampler, pass split: whatever the add-on sets at run time), seeds `Plan.equal_seeds` (1, 2, 3),
  timed (the F12 call, after one untimed render of seed 0); Cycles at its own F12 defaults
  (adaptive sampling, indirect clamp, glossy filter, OIDN with albedo and normal) with its time
  limit (`scene.cycles.time_limit`, which counts sampling only: sync and denoising come on top,
  which favours Cycles) set to styletrace's identity median time, and the converged image's light
  paths and film (64 bounces, a one-pixel box filter). Error: pooled over the seeds. cel has no
  Cycles counterpart: its goal is to be no further from its converged image than identity is from
  its own. styletrace's equal-time images are also compared with two renders of the same defaults
  at `Plan.ref_limit` (1024) Samples ("the defaults at Samples 1024": the method's own limit at
  that budget, denoiser and firefly control included), which separates the noise that more
  samples remove from what the method itself changes in the converged image.
- Goals (issue 46): raw error per sample within 1 dB of Cycles' at 64 and 1024 samples; at equal
  time identity at least as close to its converged image as Cycles; cel no worse than identity.

References are cached in benchmarks/.cache/accuracy/ (an .npy per scene, renderer, style, kind,
size, samples and seed), keyed by the code that rendered them (styletrace: the last commit of src/
and a hash of its uncommitted changes; Cycles: Blender's version) and the scenes' source; delete
the folder to recompute. A full run (128 x 128, three scenes, nothing cached) takes about 30
minutes on 2 idle cores (styletrace's references and 1024-sample renders two thirds of it, Cycles'
the rest). --quick renders a tiny smoke run (32 x 32 unless --size, a few samples) and never writes
BENCHMARKS.md. Writes the section "accuracy" of BENCHMARKS.md unless --no-write.
"""
from __future__ import annotations

import argparse
import hashlib
import json
import math
import os
import re
import statistics
import tempfile
import time

import _accuracy_scenes as A
import bpy
import numpy as np
from _report import machine_description, write_section
from real_scenes import code_version

import styletrace.blender as addon
from styletrace.blender import f12 as f12_run

HERE = os.path.dirname(os.path.abspath(__file__))
CACHE = os.path.join(HERE, ".cache", "accuracy")
#: tests/blender/scenes.py: its renderers (`cycles`, `f12`)
S = A.S
#: what decides a styletrace reference: the renderer and the add-on (not the preview server)
CODE_PATHS = ("src", "pyproject.toml", "constraints-blender.txt",
              ":(exclude)src/styletrace/preview")
PEAK = 1.0
RAW_SEED = 7
REF_SEEDS = (1001, 1002)


class Plan:
    """The sample counts and seeds of one run (full or --quick).

    Args:
        quick: the smoke run's counts.
    """

    def __init__(self, quick: bool):
        #: samples per pixel of the raw renders
        self.raw_spp = (4, 16) if quick else (64, 1024)
        #: the equal-time renders' seeds, each timed (seed 0 renders first, untimed)
        self.equal_seeds = (1,) if quick else (1, 2, 3)
        #: the converged references: Cycles' and identity's samples, cel's (camera samples,
        #: children)
        self.ref_cycles = 64 if quick else 1024
        self.ref_identity = 128 if quick else 4096
        self.ref_cel = (4, 32) if quick else (16, 256)
        #: the Samples of the defaults' own limit (`styletrace_references`)
        self.ref_limit = 64 if quick else 1024


START = time.perf_counter()


def say(*args) -> None:
    print(f"accuracy [{time.perf_counter() - START:6.0f} s]:", *args, flush=True)


# ---- the error estimate ----------------------------------------------------------------------

def clipped(img: np.ndarray) -> np.ndarray:
    """An image's RGB as float64, clipped to [0, PEAK]."""
    return np.clip(np.asarray(img, dtype=np.float64)[..., :3], 0.0, PEAK)


def error(images: list[np.ndarray], r1: np.ndarray, r2: np.ndarray) -> tuple[float, float]:
    """The squared error of images against the converged image that r1 and r2 estimate.

    Args:
        images: renders of one setting (their seeds not the references'); pooled.
        r1, r2: two independent converged references of the same renderer and style.

    Returns:
        (mean of (d - r1)(d - r2) over the images, pixels and channels, its standard error from
        the spread of the per-pixel means over the pixels).
    """
    a, b = clipped(r1), clipped(r2)
    per_pixel = np.mean([((clipped(d) - a) * (clipped(d) - b)).mean(axis=-1) for d in images],
                        axis=0)
    return float(per_pixel.mean()), float(per_pixel.std(ddof=1) / math.sqrt(per_pixel.size))


def reference_error(r1: np.ndarray, r2: np.ndarray) -> tuple[float, float]:
    """The squared error one reference has left: mean((r1 - r2)^2) / 2.

    Args:
        r1, r2: two independent references of the same expectation.

    Returns:
        (the estimate, its standard error from the pixels' spread).
    """
    per_pixel = ((clipped(r1) - clipped(r2)) ** 2).mean(axis=-1) / 2
    return float(per_pixel.mean()), float(per_pixel.std(ddof=1) / math.sqrt(per_pixel.size))


def psnr(mse: float) -> float:
    """10 log10(PEAK^2 / mse), in dB (mse > 0)."""
    return 10 * math.log10(PEAK * PEAK / mse)


def db(est: tuple[float, float]) -> str:
    """A PSNR with its standard error in dB; a lower bound where the error is not resolved (at
    or below two standard errors).

    Args:
        est: (squared error, its standard error).

    Returns:
        e.g. "31.2 +- 0.1 dB", or "> 48.0 dB".
    """
    mse, se = est
    if mse <= 2 * se:
        return f"> {psnr(mse + 2 * se):.1f} dB" if mse + 2 * se > 0 else "inf"
    return f"{psnr(mse):.1f} +- {10 / math.log(10) * se / mse:.1f} dB"


def gap(a: tuple[float, float], b: tuple[float, float]) -> float | None:
    """PSNR of `a` minus that of `b` in dB (positive: `a` is closer to its converged image), None
    where either is not resolved."""
    if a[0] <= 2 * a[1] or b[0] <= 2 * b[1]:
        return None
    return psnr(a[0]) - psnr(b[0])


# ---- rendering -------------------------------------------------------------------------------

def build(name: str, size: int):
    """A fresh scene `name` at size x size (every setting at its factory default)."""
    return A.SCENES[name](size)


def timed_f12(path: str) -> tuple[np.ndarray, float]:
    """F12 on the current scene, written to the EXR `path`: (its image, H x W x 3, and the
    seconds of the render and the write, not of reading it back)."""
    bpy.context.scene.render.filepath = path
    start = time.perf_counter()
    bpy.ops.render.render(write_still=True)
    seconds = time.perf_counter() - start
    return S.read_exr(path)["Combined"][..., :3], seconds


def styletrace_settings(style: str, seed: int, **settings):
    """The styletrace engine on the current scene, with `style`, `seed` and `settings` given and
    every other setting the add-on's default."""
    scene = bpy.context.scene
    scene.render.engine = "STYLETRACE"
    st = scene.styletrace
    st.style, st.seed = style, seed
    for key, value in settings.items():
        setattr(st, key, value)
    return st


def cycles_equal_time(seed: int, seconds: float) -> None:
    """Cycles on the current scene at its F12 defaults (adaptive sampling, clamping, OIDN), with
    its time limit, and the converged image's film and bounces (`scenes.cycles`)."""
    scene = bpy.context.scene
    scene.render.engine = "CYCLES"
    c = scene.cycles
    c.device, c.seed, c.time_limit = "CPU", seed, seconds
    c.use_denoising, c.denoiser = True, "OPENIMAGEDENOISE"
    c.pixel_filter_type, c.filter_width = "BOX", 1.0
    c.max_bounces = c.diffuse_bounces = c.glossy_bounces = c.transmission_bounces = 64
    c.transparent_max_bounces = 64


def describe() -> dict:
    """What the styletrace engine would run on the current scene with its current settings: the
    denoising method, the auto values (the split first), the sampler of the exported scene.

    Returns:
        {"method", "auto", "sampler"}; "?" where the pipeline could not be asked (its message
        printed).
    """
    st = bpy.context.scene.styletrace
    try:
        sc = f12_run.scene(bpy.context.evaluated_depsgraph_get(), st, warn=lambda _: None)
        resolved = f12_run.run_f12(sc, st, f12_run.error_passes(st)).resolved
        # the plugin's class, e.g. IndependentSampler (`class_name` names the base class)
        sampler = repr(resolved.scene.sensors()[0].sampler()).split("[")[0].strip()
        return {"method": resolved.method, "auto": resolved.auto, "sampler": sampler}
    except Exception as exc:  # a description only: the render itself reports its own errors
        say(f"could not describe the run: {type(exc).__name__}: {exc}")
        return {"method": "?", "auto": "?", "sampler": "?"}


def cel_values(auto: str) -> str:
    """cel's resolved thresholds and levels in an auto-values line ('' if none)."""
    return "; ".join(p for p in auto.split("; ") if p.startswith("cel "))


def sampler_choice() -> tuple[str, str] | None:
    """(the property, its default) where the add-on lets a user choose the sampler and
    `independent` is a choice but not the default; else None."""
    props = bpy.context.scene.styletrace.bl_rna.properties
    for prop in props:
        if "sampler" in prop.identifier and prop.type == "ENUM":
            items = [i.identifier for i in prop.enum_items]
            if "independent" in items and prop.default != "independent":
                return prop.identifier, prop.default
    return None


# ---- the references --------------------------------------------------------------------------

def digest(*parts) -> str:
    """12 hex digits of a hash of `parts` (JSON) and the scenes' source (`source_files`)."""
    h = hashlib.sha256(json.dumps(parts, sort_keys=True, default=str).encode())
    for path in A.source_files():
        with open(path, "rb") as f:
            h.update(f.read())
    return h.hexdigest()[:12]


def cached(key: dict, render) -> np.ndarray:
    """The reference of `key` from the cache, else rendered (`render()`, H x W x 3) and kept."""
    os.makedirs(CACHE, exist_ok=True)
    label = "-".join(str(key[k]) for k in ("scene", "renderer", "style", "kind", "size", "count",
                                           "seed"))
    label = re.sub(r"[^A-Za-z0-9.-]+", "_", label)  # file names without spaces
    path = os.path.join(CACHE, f"{label}-{digest(key)}.npy")
    if os.path.exists(path):
        return np.load(path)
    start = time.perf_counter()
    img = np.asarray(render(), dtype=np.float32)
    np.save(path + ".tmp.npy", img)
    os.replace(path + ".tmp.npy", path)  # a run stopped mid-write leaves no half file
    say(f"  {label}: {time.perf_counter() - start:.1f} s")
    return img


def styletrace_references(plan: Plan) -> dict:
    """styletrace's references: {(style, kind): (their samples in words, the engine settings)}.

    Kinds: "converged", the style's converged image (identity: no denoising; cel: direct
    application at a large inner count); "limit", the add-on's defaults at `Plan.ref_limit`
    Samples (the pass split aside, which changes no expectation): where the defaults' method
    converges to at that budget, denoiser and firefly control included.

    Args:
        plan: the run's counts.

    Returns:
        The setups.
    """
    cel_spp, cel_n = plan.ref_cel
    limit = (f"Samples {plan.ref_limit}, defaults", dict(samples=plan.ref_limit, pass_spp=16))
    return {
        ("identity", "converged"): (
            f"{plan.ref_identity} spp",
            dict(samples=plan.ref_identity, denoise="off", aovs=False, pass_spp=64)),
        ("cel", "converged"): (
            f"{cel_spp} camera samples x {cel_n} children",
            dict(spp=cel_spp, inner_samples=str(cel_n), denoise="off", aovs=False)),
        ("identity", "limit"): limit,
        ("cel", "limit"): limit,
    }


def references(name: str, size: int, plan: Plan, tmp: str, code: str) -> tuple[dict, ...]:
    """The references of scene `name`, each of two seeds (REF_SEEDS), from the cache or rendered.

    Args:
        name: the scene. size: its side. plan: the run's counts. tmp: a folder for EXRs.
        code: styletrace's code version (part of its references' keys).

    Returns:
        ({(renderer, style, kind): [r1, r2]}, {same key: their samples in words}, {styletrace's
        keys: the auto values of its run, from `describe`}); renderer "styletrace" or "cycles"
        (identity, converged only), kind "converged" or "limit" (`styletrace_references`).
    """
    out, what, auto = {}, {}, {}
    exr = os.path.join(tmp, "ref.exr")
    for (style, kind), (label, settings) in styletrace_references(plan).items():
        def render(seed, style=style, settings=settings):
            build(name, size)
            styletrace_settings(style, seed, **settings)
            return S.f12(exr)["Combined"][..., :3]
        key = ("styletrace", style, kind)
        build(name, size)
        styletrace_settings(style, REF_SEEDS[0], **settings)
        auto[key] = describe()["auto"]  # cel's resolved values, checked in `notes`
        out[key] = [
            cached(dict(scene=name, renderer="styletrace", style=style, kind=kind, size=size,
                        count=label, seed=seed, code=code, settings=settings),
                   lambda seed=seed, render=render: render(seed)) for seed in REF_SEEDS]
        what[key] = label

    def cycles(seed):
        build(name, size)
        return S.cycles(exr, plan.ref_cycles, seed=seed)
    key = ("cycles", "identity", "converged")
    out[key] = [
        cached(dict(scene=name, renderer="cycles", style="identity", kind="converged", size=size,
                    count=f"{plan.ref_cycles} spp", seed=seed, blender=bpy.app.version_string,
                    settings="scenes.cycles"), lambda seed=seed: cycles(seed))
        for seed in REF_SEEDS]
    what[key] = f"{plan.ref_cycles} spp"
    return out, what, auto


# ---- the measures ----------------------------------------------------------------------------

def raw_styletrace(name: str, size: int, style: str, spp: int, tmp: str, warm: bool,
                   **settings) -> dict:
    """One raw styletrace render: Denoise Off, `spp` Samples, seed RAW_SEED, `settings` given.

    Args:
        name: the scene. size: its side. style: identity or cel. spp: the Samples. tmp: a
            folder for the EXR. warm: one untimed render of the same settings first.
        **settings: more engine settings (the sampler's).

    Returns:
        {"images": [image], "seconds", "method", "auto", "sampler"} (`describe`).
    """
    exr = os.path.join(tmp, "raw.exr")
    build(name, size)
    styletrace_settings(style, RAW_SEED, samples=spp, denoise="off", **settings)
    info = describe()
    if warm:
        styletrace_settings(style, RAW_SEED + 1)
        timed_f12(exr)
        styletrace_settings(style, RAW_SEED)
    img, seconds = timed_f12(exr)
    return {"images": [img], "seconds": seconds, **info}


def raw_cycles(name: str, size: int, spp: int, tmp: str) -> dict:
    """One raw Cycles render of `spp` samples (`scenes.cycles`' settings), timed as F12
    (`timed_f12`).

    Returns:
        {"images": [image], "seconds"}.
    """
    exr = os.path.join(tmp, "raw-cycles.exr")
    build(name, size)
    S.cycles(exr, 1, seed=RAW_SEED)  # its settings (and an untimed render of 1 sample)
    bpy.context.scene.cycles.samples = spp
    img, seconds = timed_f12(exr)
    return {"images": [img], "seconds": seconds}


def equal_styletrace(name: str, size: int, style: str, seeds, tmp: str) -> dict:
    """F12 at the add-on's defaults but the style: seed 0 untimed, then `seeds`, timed.

    Returns:
        {"images", "seconds" (the median), "times", "method", "auto", "sampler"}.
    """
    exr = os.path.join(tmp, "equal.exr")
    build(name, size)
    styletrace_settings(style, 0)
    st = bpy.context.scene.styletrace
    info = describe()
    timed_f12(exr)
    images, times = [], []
    for seed in seeds:
        st.seed = seed
        img, seconds = timed_f12(exr)
        images.append(img)
        times.append(seconds)
    return {"images": images, "seconds": statistics.median(times), "times": times, **info}


def equal_cycles(name: str, size: int, seconds: float, seeds, tmp: str) -> dict:
    """Cycles with its time limit at `seconds` (`cycles_equal_time`): seed 0 untimed (OIDN's
    first load), then `seeds`.

    Returns:
        {"images", "seconds" (the median wall time), "times", "limit"}.
    """
    exr = os.path.join(tmp, "equal-cycles.exr")
    build(name, size)
    cycles_equal_time(0, seconds)
    timed_f12(exr)
    images, times = [], []
    for seed in seeds:
        bpy.context.scene.cycles.seed = seed
        img, wall = timed_f12(exr)
        images.append(img)
        times.append(wall)
    return {"images": images, "seconds": statistics.median(times), "times": times,
            "limit": seconds}


def measure_scene(name: str, size: int, plan: Plan, tmp: str, code: str) -> dict:
    """Every measure of one scene.

    Returns:
        {"refs", "ref_what", "ref_auto" (`references`), "rows": {(measure, column): row}}, each
        row with "error" against its converged image and, for styletrace's equal-time rows,
        "error_limit" against the defaults at `Plan.ref_limit` Samples.
    """
    say(f"{name}: references (cached after the first run)")
    refs, ref_what, ref_auto = references(name, size, plan, tmp, code)
    rows: dict = {}
    independent = sampler_choice()
    for k, spp in enumerate(plan.raw_spp):
        say(f"{name}: raw, {spp} samples")
        for style in ("identity", "cel"):
            rows[(f"raw {spp}", f"styletrace {style}")] = raw_styletrace(
                name, size, style, spp, tmp, warm=k == 0)
        if independent is not None:
            prop, _ = independent
            rows[(f"raw {spp}", "styletrace identity, independent")] = raw_styletrace(
                name, size, "identity", spp, tmp, warm=k == 0, **{prop: "independent"})
        rows[(f"raw {spp}", "Cycles")] = raw_cycles(name, size, spp, tmp)
    say(f"{name}: equal time, the add-on's defaults")
    for style in ("identity", "cel"):
        rows[("equal", f"styletrace {style}")] = equal_styletrace(
            name, size, style, plan.equal_seeds, tmp)
    limit = rows[("equal", "styletrace identity")]["seconds"]
    rows[("equal", "Cycles")] = equal_cycles(name, size, limit, plan.equal_seeds, tmp)
    for (measure, column), row in rows.items():
        style = "cel" if "cel" in column else "identity"
        renderer = "cycles" if column == "Cycles" else "styletrace"
        row["error"] = error(row["images"], *refs[(renderer, style, "converged")])
        if measure == "equal" and renderer == "styletrace":
            row["error_limit"] = error(row["images"], *refs[(renderer, style, "limit")])
        say(f"{name}: {measure}, {column}: {db(row['error'])}, {row['seconds']:.2f} s"
            + (f" ({row['method']}; {row['auto']}; {row['sampler']})" if "auto" in row else ""))
    return {"refs": refs, "ref_what": ref_what, "ref_auto": ref_auto, "rows": rows}


# ---- the report ------------------------------------------------------------------------------

def scene_table(result: dict, plan: Plan) -> str:
    """One scene's Markdown table: a column per renderer and style, a row per measure.

    Args:
        result: `measure_scene`'s. plan: the run's counts.

    Returns:
        The table.
    """
    rows = result["rows"]
    columns = list(dict.fromkeys(c for _, c in rows))
    out = ["| | " + " | ".join(columns) + " |", "|---|" + "---|" * len(columns)]
    for spp in plan.raw_spp:
        cells = []
        for c in columns:
            r = rows.get((f"raw {spp}", c))
            cells.append("-" if r is None else f"{db(r['error'])}, {r['seconds']:.2f} s")
        out.append(f"| raw, {spp} samples: PSNR, time per image | " + " | ".join(cells) + " |")
    cells = []
    for c in columns:
        r = rows.get(("equal", c))
        if r is None:
            cells.append("-")
        elif c == "Cycles":
            cells.append(f"{db(r['error'])}, limit {r['limit']:.2f} s, wall {r['seconds']:.2f} s")
        else:
            cells.append(f"{db(r['error'])}, {r['seconds']:.2f} s ({r['method']})")
    out.append("| equal time, defaults: PSNR, time | " + " | ".join(cells) + " |")
    cells = [db(rows[("equal", c)]["error_limit"]) if "error_limit" in rows.get(("equal", c), {})
             else "-" for c in columns]
    out.append(f"| equal time, defaults, against the defaults at Samples {plan.ref_limit}: PSNR | "
               + " | ".join(cells) + " |")
    for kind, title in (("converged", "one converged reference"),
                        ("limit", f"one reference of the defaults at Samples {plan.ref_limit}")):
        cells = []
        for c in columns:
            key = ("cycles" if c == "Cycles" else "styletrace",
                   "cel" if "cel" in c else "identity", kind)
            if "independent" in c:
                cells.append("identity's")
            elif key not in result["refs"]:
                cells.append("-")
            else:
                cells.append(f"{db(reference_error(*result['refs'][key]))} "
                             f"({result['ref_what'][key]})")
        out.append(f"| {title}: PSNR of its noise (samples) | " + " | ".join(cells) + " |")
    return "\n".join(out)


def verdict(ok: bool | None) -> str:
    """A goal's state in words."""
    return "not resolved" if ok is None else ("met" if ok else "NOT met")


def goals(result: dict, plan: Plan) -> list[str]:
    """The issue's goals on one scene, each checked on the PSNR estimates (a line each).

    Args:
        result: `measure_scene`'s. plan: the run's counts.

    Returns:
        The lines.
    """
    rows = result["rows"]
    out = []
    for spp in plan.raw_spp:
        cy = rows[(f"raw {spp}", "Cycles")]["error"]
        parts = []
        for c in ("styletrace identity", "styletrace cel"):
            g = gap(rows[(f"raw {spp}", c)]["error"], cy)
            parts.append(f"{c.split()[1]} {'?' if g is None else f'{g:+.1f}'} dB "
                         f"({verdict(None if g is None else g >= -1.0)})")
        out.append(f"raw error per sample within 1 dB of Cycles' (PSNR at most 1 dB below) at "
                   f"{spp} samples: " + ", ".join(parts))
    ident, cel = rows[("equal", "styletrace identity")], rows[("equal", "styletrace cel")]
    g = gap(ident["error"], rows[("equal", "Cycles")]["error"])
    out.append(f"equal time, identity at least as close as Cycles: "
               f"{'?' if g is None else f'{g:+.1f}'} dB ({verdict(None if g is None else g >= 0)})")
    parts = []
    for field, against in (("error", "each against its converged image"),
                           ("error_limit", f"each against the defaults at Samples "
                                           f"{plan.ref_limit}")):
        g = gap(cel[field], ident[field])
        parts.append(f"{'?' if g is None else f'{g:+.1f}'} dB {against} "
                     f"({verdict(None if g is None else g >= 0)})")
    out.append("equal time, cel no worse than identity: " + "; ".join(parts))
    return out


def notes(result: dict) -> list[str]:
    """The runs' splits and samplers, and checks: cel's resolved values the same in every run and
    in its references, references that differ, the two renderers' converged means.

    Args:
        result: `measure_scene`'s.

    Returns:
        The lines.
    """
    rows, refs = result["rows"], result["refs"]
    out = []
    for (measure, column), r in rows.items():
        if "auto" in r:
            out.append(f"{measure}, {column}: {r['method']}, sampler {r['sampler']}; {r['auto']}")
    cels = {cel_values(r["auto"]) for (_, c), r in rows.items() if "cel" in c and "auto" in r}
    for kind in ("converged", "limit"):
        auto = result["ref_auto"][("styletrace", "cel", kind)]
        cels.add(cel_values(auto))
        out.append(f"cel's {kind} references: {auto}")
    if len(cels) > 1:
        out.append("WARNING: cel's resolved thresholds and levels differ between runs: "
                   + " | ".join(sorted(cels)))
    for key, (r1, r2) in refs.items():
        if np.array_equal(r1, r2):
            out.append(f"WARNING: {' '.join(key)}: the two references are identical: their seeds "
                       "do not decorrelate the sampler, so the estimate keeps their error")
    st = np.mean(refs[("styletrace", "identity", "converged")], axis=0).mean(axis=(0, 1))
    cy = np.mean(refs[("cycles", "identity", "converged")], axis=0).mean(axis=(0, 1))
    out.append("converged identity means, styletrace / Cycles (not a goal; the scenes agree): "
               + ", ".join(f"{v:.3f}" for v in st / cy))
    return out


def report(results: dict, size: int, plan: Plan, code: str) -> str:
    """The BENCHMARKS.md section: machine and versions, the protocol in short, per scene its
    table, goals and notes.

    Args:
        results: {scene: `measure_scene`'s}. size: the image side. plan: the run's counts.
        code: styletrace's code version (`real_scenes.code_version`).

    Returns:
        The section's Markdown.
    """
    st = bpy.context.scene.styletrace
    threads = "?"
    try:
        import drjit as dr
        threads = str(dr.thread_count())
    except Exception:
        pass
    body = [
        "## Accuracy against Cycles (`benchmarks/accuracy.py`)",
        "",
        machine_description() + f"; Blender {bpy.app.version_string} (bpy), Cycles on the CPU "
        f"with 2 threads, Dr.Jit {threads} threads; styletrace's code {code} (`real_scenes."
        "code_version`: the last commit of src/, + a hash of uncommitted changes)",
        "",
        f"{size}x{size}. Each image against its own renderer's converged image: error = mean "
        "of (d - r1)(d - r2) over pixels and channels, with two references r1, r2 of other seeds "
        f"(their noise cancels in expectation), every image clipped to [0, {PEAK:g}] (linear; "
        f"peak {PEAK:g}); PSNR = 10 log10(peak^2 / error), +- one standard error. Converged: "
        "identity and Cycles without denoising or clamping; cel by direct application at a large "
        "inner count, which has not converged on these interiors (its mean of 256 children still "
        "flips cel's narrow auto bands from pixel to pixel), so cel is also judged against the "
        f"defaults at Samples {plan.ref_limit}. Raw: Denoise Off, the Samples given, other "
        "settings the add-on's defaults "
        "(cel's error includes its children's bias at band edges). Equal time: styletrace's F12 "
        f"at the add-on's defaults (Samples {st.samples}, Denoise {st.denoise}, passes from "
        f"{st.pass_spp} camera samples, doubling with the {st.sampler} pattern), median time "
        f"of {len(plan.equal_seeds)} seed(s); Cycles at its F12 "
        "defaults (adaptive, clamp, OIDN) with its time limit set to styletrace identity's time "
        "(sampling only: wall time shown), a one-pixel box filter and 64 bounces as its "
        "reference. Also for styletrace's equal-time images: the error against the same defaults "
        f"at Samples {plan.ref_limit} (two seeds), which leaves out what the defaults' method "
        "(denoiser, firefly control) changes in the converged image: the part of the error that "
        "more samples would remove. The script's docstring gives the protocol.",
    ]
    for name, result in results.items():
        body += ["", f"### {name}", "", scene_table(result, plan), ""]
        body += [f"- {g}" for g in goals(result, plan)]
        body += [f"- {n}" for n in notes(result)]
    return "\n".join(body)


def main() -> None:
    """The command line (the module docstring).

    Raises:
        SystemExit: an unknown scene name.
    """
    ap = argparse.ArgumentParser(
        description="Accuracy against Cycles: styletrace's identity and cel styles and Cycles, "
        "each against its own converged image, on three Blender scenes (the module docstring).")
    ap.add_argument("--size", type=int, default=None, help="image side (128; --quick: 32)")
    ap.add_argument("--scenes", default=",".join(A.SCENES),
                    help=f"comma-separated, of {', '.join(A.SCENES)}")
    ap.add_argument("--quick", action="store_true", help="a tiny smoke run (never written)")
    ap.add_argument("--no-write", action="store_true", help="print the section, not written")
    args = ap.parse_args()
    plan = Plan(args.quick)
    size = args.size or (32 if args.quick else 128)
    names = [n for n in args.scenes.split(",") if n]
    unknown = [n for n in names if n not in A.SCENES]
    if unknown:
        raise SystemExit(f"accuracy: unknown scene(s) {', '.join(unknown)}: choose from "
                         f"{', '.join(A.SCENES)}")
    if os.environ.get("STYLETRACE_DENOISE"):
        say(f"note: $STYLETRACE_DENOISE={os.environ['STYLETRACE_DENOISE']} sets the add-on's "
            "default Denoise")
    addon.register()
    code = code_version(paths=CODE_PATHS)
    say(f"{size}x{size}, scenes {', '.join(names)}, styletrace code {code}"
        + (" (quick)" if args.quick else ""))
    results = {}
    with tempfile.TemporaryDirectory() as tmp:
        for name in names:
            results[name] = measure_scene(name, size, plan, tmp, code)
    body = report(results, size, plan, code)
    print(body, flush=True)
    if args.quick or args.no_write:
        say("not written" + (" (--quick)" if args.quick else " (--no-write)"))
    else:
        write_section("accuracy", body)
        say("written to BENCHMARKS.md")
    say("done")


if __name__ == "__main__":
    main()
