"""Animation (issue 47): how much a still shot's frames flicker, with and without temporal reuse
(docs/temporal.md), against Cycles. Run with the Blender venv (bpy as a module), on an otherwise
idle machine:

    .venv-blender/bin/python benchmarks/temporal.py [--size 256] [--frames 8] [--quick]
        [--no-write] [--no-figure] [--no-moving] [--moving-size 128] [--no-eevee] [--no-floor]
        [--eevee-frames 3]

Protocol: the tests' interior lit through a window (tests/blender/scenes.py `interior`: a sun and a
sky through the window, a small area lamp, a glossy floor, a mirror), nothing animated, rendered
with Render Animation (`bpy.ops.render.render(animation=True)`) over frames 1..F into EXR files:
- styletrace at the add-on's defaults (Samples 16, Denoise auto, seed per frame) for identity, cel,
  hatching and colour map (and, on the still shot only, the other step styles, half-tone and
  tie-dye), with Temporal reuse off (the frames as before) and on;
- Cycles at 16 samples, OIDN, animated seed, 2 threads, its other defaults;
- EEVEE (Blender 5.0's EEVEE Next) at its defaults, with the scene's own materials, and toon:
  every material's surface through Shader to RGB and a constant ColorRamp into an Emission, with
  cel's default bands read off EEVEE's own first frame (`cel_bands`, `toon_materials`); each after
  one render of frame 1 timed apart (`eevee`), over EEVEE_FRAMES frames (EEVEE is deterministic,
  and slow on this machine's software OpenGL).
Measures, each over the F - 1 pairs of consecutive frames:
- flicker, two ways: the share of pixels whose display-space brightness (the luminance of the
  sRGB-encoded image) changes by more than 10% of the larger of the two (brightness below 0.05
  counts as 0.05, so that near-black noise is not a change); and the share of pixels one of whose
  display-space channels changes by more than 0.1 (of the display's range);
- the error of frame k against the converged image (styletrace: two renders of the same defaults
  at Samples REF_SAMPLES with their own seeds, mean((d - r1)(d - r2)) over clipped linear pixels,
  so that the references' noise cancels; as PSNR);
- seconds per frame: the animation's wall time over F; on the still shot each styletrace
  animation runs TIMINGS times, reuse off and on in turn, and the fastest counts (the cost of
  reuse is of the order of this machine's noise).
Moving shots (unless --no-moving): the still life (benchmarks/_accuracy_scenes.py) with the camera
orbiting its target by ORBIT_DEG a frame, and the interior with a sphere rolling across the floor
by ROLL a frame; warping error (Lai et al., "Learning Blind Video Temporal Consistency", ECCV
2018): the mean over consecutive frames and over the pixels seen in both of the squared difference
between frame t and frame t - 1 warped to it along the renderer's own Vector pass (bilinear; a
pixel whose surface was behind another one in frame t - 1, by the Depth pass, 10% apart, is left
out), display-space values; also on the tone (both frames blurred over hatching's line spacing, 8
pixels, the blur normalised at the borders: hatching's pattern stays on the screen by design, so
hatching is judged on its tone against identity's tone). EEVEE's Vector pass follows the same
convention in X, Y (checked once, 48 x 48, 3 frames: on both shots the error with X, Y as written
is 3 to 5 times below that with them negated, and about half that with Z, W, which hold the
motion to the next frame with the same sign, cur - next, and are not used); its Depth pass reads
about the camera's clip end where no surface is, taken as none (`depth_of`). The measure's
floor (unless --no-floor): the warping error of the frames' expected images, without their noise:
each style rendered twice at Samples REF_SAMPLES_MOVING, reuse off, with two other seeds, and
mean((b1 - W a1)(b2 - W a2)) over the pixels seen in both (`clean_warp_error`): what a renderer
that converges to the right frames cannot go below (the lighting that really changes from frame
to frame, and the warp's own resampling of sharp edges).
Goals (issue 47, still shot): cel and colour map at most 0.5% of pixels changing by more than 10%
per frame, hatching at most 1%, identity at most Cycles'; cost per frame at most 1.1x without reuse;
the first frame unchanged (it has no earlier frame; the table gives the largest difference of its
pixels between the two runs, OIDN's float rounding from run to run). Temporal reuse's constants
(Z, CAP) were chosen on the Cornell box (tests/denoise/test_temporal_frames.py), not on this
scene. Moving shots: warping error of cel and colour map at most 1.2x identity's and at most half
of today's (reuse off); hatching the same on its tone against identity's tone. The goal column
also gives the ratio against identity without reuse (today's), and the floor's ratio (style /
identity, both expected frames): whether 1.2x is reachable by a renderer that converges to the
right images.

Writes the section "temporal" of BENCHMARKS.md unless --no-write, and docs/temporal.png (two
consecutive cel frames and their difference, without and with reuse) unless --no-figure.
"""
from __future__ import annotations

import argparse
import os
import sys
import tempfile
import time

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(os.path.dirname(HERE), "tests", "blender"))

import bpy  # noqa: E402
import numpy as np  # noqa: E402
import scenes as S  # noqa: E402
from _report import machine_description, write_section  # noqa: E402

import styletrace.blender as addon  # noqa: E402
from styletrace.measures import srgb  # noqa: E402
from styletrace.styles.base import increasing  # noqa: E402
from styletrace.styles.cel import Cel  # noqa: E402
from styletrace.styles.tone import band_levels  # noqa: E402

STYLES = ("identity", "cel", "hatching", "color_map")
#: the references' Samples (the defaults' method converged at that budget) and seeds
REF_SAMPLES = 512
REF_SEEDS = (1001, 1002)
SEED = 0
GOALS = {"cel": 0.005, "color_map": 0.005, "hatching": 0.01, "halftone": 0.01,
         "tie_dye": 0.005}
#: the moving shots: the camera's turn about the still life's target per frame, the sphere's roll
ORBIT_DEG = 1.5
ROLL = 0.15
#: hatching's tone: the blur over its default line spacing (pixels)
TONE = 8
#: the moving shots' converged frames (the measure's floor): Samples, reuse off
REF_SAMPLES_MOVING = 256
#: the seeds of the two renders whose noise cancels in the floor (`clean_warp_error`): frame f
#: renders with seed + f - 1, so they are far apart (seeds 1001 and 1002 gave run 2's frame f - 1
#: run 1's frame f's seed: their noise, the same at every still pixel, did not cancel)
FLOOR_SEEDS = (1001, 5001)
#: styles on the still shot only (their flicker): the other step styles
STILL_ONLY = ("halftone", "tie_dye")
#: EEVEE renders this many frames by default (it is deterministic, and slow on software OpenGL)
EEVEE_FRAMES = 3
#: each still-shot animation of styletrace is timed this many times, with reuse off and on in
#: turn; seconds a frame is the fastest (the machine's noise was of the order of the cost)
TIMINGS = 2
#: EEVEE toon's bands: cel's default number (`cel_bands`)
CEL_BANDS = next(p.default for p in Cel.params if p.name == "bands")
EEVEE_NAME = "EEVEE (Blender 5.0 EEVEE Next, its defaults)"
TOON_NAME = "EEVEE toon, Shader to RGB"


def say(*args) -> None:
    print("temporal:", *args, flush=True)


def luminance(img: np.ndarray) -> np.ndarray:
    return img[..., 0] * 0.2126 + img[..., 1] * 0.7152 + img[..., 2] * 0.0722


def flicker(a: np.ndarray, b: np.ndarray) -> tuple[float, float]:
    """(relative, absolute) shares of pixels that changed between two frames (module doc).

    Args:
        a, b: H x W x 3 linear frames.

    Returns:
        Two floats in [0, 1].
    """
    da, db = srgb(a[..., :3]), srgb(b[..., :3])
    la, lb = luminance(da), luminance(db)
    top = np.maximum(np.maximum(la, lb), 0.05)
    rel = float(np.mean(np.abs(la - lb) > 0.1 * top))
    absolute = float(np.mean(np.abs(da - db).max(axis=-1) > 0.1))
    return rel, absolute


def warped(prev: np.ndarray, vector: np.ndarray, depth_prev: np.ndarray, depth: np.ndarray):
    """Frame t - 1 carried to frame t along t's Vector pass (Blender's: x_prev - x, y_prev - y in
    pixels, y up), bilinear, and where it is seen in both (inside frame t - 1, a surface in t, and
    its depth in t - 1 within 10% of t's: not behind another surface).

    Returns:
        (the warped frame H x W x C, the mask H x W).
    """
    h, w = depth.shape
    cols, rows = np.meshgrid(np.arange(w, dtype=np.float64), np.arange(h, dtype=np.float64))
    x, y = cols + vector[..., 0], rows - vector[..., 1]
    x0, y0 = np.floor(x).astype(int), np.floor(y).astype(int)
    fx, fy = x - x0, y - y0
    out = np.zeros(prev.shape)
    dep = np.zeros((h, w))
    inside = (x0 >= 0) & (x0 < w - 1) & (y0 >= 0) & (y0 < h - 1)
    xc, yc = np.clip(x0, 0, w - 2), np.clip(y0, 0, h - 2)
    for dx, dy, c in ((0, 0, (1 - fx) * (1 - fy)), (1, 0, fx * (1 - fy)), (0, 1, (1 - fx) * fy),
                      (1, 1, fx * fy)):
        out += c[..., None] * prev[yc + dy, xc + dx]
        dep += c * depth_prev[yc + dy, xc + dx]
    seen = inside & (depth < 1e9) & (np.abs(dep - depth) <= 0.1 * depth)
    return out, seen


def box_blur(img: np.ndarray, size: int) -> np.ndarray:
    """The mean over the size x size box about each pixel, of the pixels inside the image.

    Dividing by the share of the box inside the image (the blurred ones) keeps a flat image flat
    up to its borders: zero padding would darken them, and a warp that shifts the image by a
    pixel would then count that darkening as error.

    Args:
        img: H x W or H x W x C.
        size: the box's side in pixels.

    Returns:
        An array of img's shape.
    """
    k = np.ones(size)

    def blur(a):
        out = np.apply_along_axis(lambda v: np.convolve(v, k, mode="same"), 0, a)
        return np.apply_along_axis(lambda v: np.convolve(v, k, mode="same"), 1, out)

    inside = blur(np.ones(img.shape[:2]))
    return blur(img) / (inside[..., None] if img.ndim == 3 else inside)


def warp_error(frames: list, tone: bool = False) -> float:
    """The warping error of a moving shot's frames (module doc), display space.

    Args:
        frames: [(image, vector, depth)] in order, vector as Blender's (`warped`). tone: both
            frames blurred over TONE first (`box_blur`, border-correct).

    Returns:
        The mean squared difference over pixels seen in both, over consecutive pairs.
    """
    errs = []
    for (a, _, da), (b, vb, db) in zip(frames, frames[1:]):
        pa, pb = srgb(a[..., :3]), srgb(b[..., :3])
        if tone:
            pa, pb = box_blur(pa, TONE), box_blur(pb, TONE)
        w, seen = warped(pa, vb, da, db)
        errs.append(float(np.mean(((pb - w) ** 2)[seen])))
    return float(np.mean(errs))


def clean_warp_error(one: list, two: list, tone: bool = False) -> float:
    """The warping error of a moving shot's expected frames, without their noise: with two
    renders of the same frames by other seeds, the mean over pixels seen in both of
    (b1 - W a1)(b2 - W a2), whose noise terms are independent and cancel in expectation (as
    `error` does for the error against a reference). The Vector and Depth passes are `one`'s.

    Args:
        one, two: [(image, vector, depth)] in order, the same frames by two seeds. tone: both
            blurred over TONE first.

    Returns:
        The estimate (it may come out slightly negative where the expected error is near 0).
    """
    errs = []
    for (a1, _, da), (b1, vb, db), (a2, _, _), (b2, _, _) in zip(one, one[1:], two, two[1:]):
        pa1, pb1, pa2, pb2 = (srgb(x[..., :3]) for x in (a1, b1, a2, b2))
        if tone:
            pa1, pb1, pa2, pb2 = (box_blur(x, TONE) for x in (pa1, pb1, pa2, pb2))
        w1, seen = warped(pa1, vb, da, db)
        w2, _ = warped(pa2, vb, da, db)
        errs.append(float(np.mean(((pb1 - w1) * (pb2 - w2))[seen])))
    return float(np.mean(errs))


def error(img, r1, r2) -> float:
    c = lambda x: np.clip(x[..., :3], 0.0, 1.0)  # noqa: E731
    return float(np.mean((c(img) - c(r1)) * (c(img) - c(r2))))


def psnr(mse: float) -> str:
    return "inf" if mse <= 0 else f"{10 * np.log10(1.0 / mse):.1f}"


def scene(size: int, frames: int):
    s = S.interior(size)
    s.frame_start, s.frame_end = 1, frames
    return s


def animate(s, folder: str, frames: int) -> tuple[list[np.ndarray], float]:
    """Render Animation into `folder`: (the frames, seconds per frame)."""
    s.render.filepath = os.path.join(folder, "frame_####")
    start = time.perf_counter()
    bpy.ops.render.render(animation=True)
    seconds = (time.perf_counter() - start) / frames
    images = [S.read_exr(s.render.frame_path(frame=f))["Combined"][..., :3]
              for f in range(1, frames + 1)]
    return images, seconds


def styletrace_frames(size, frames, style, reuse, folder):
    s = scene(size, frames)
    s.render.engine = "STYLETRACE"
    st = s.styletrace
    st.style, st.seed, st.temporal_reuse = style, SEED, reuse
    return animate(s, folder, frames)


def cycles_frames(size, frames, folder):
    s = scene(size, frames)
    s.render.engine = "CYCLES"
    c = s.cycles
    c.device, c.samples, c.seed, c.use_animated_seed = "CPU", 16, SEED, True
    c.use_denoising, c.denoiser = True, "OPENIMAGEDENOISE"
    return animate(s, folder, frames)


def orbit_shot(size: int, frames: int):
    """The still life, the camera turning about its target by ORBIT_DEG a frame."""
    import math

    import _accuracy_scenes as A
    s = A.still_life(size)
    cam = s.camera
    target = np.array((0.0, 0.2, 0.45))
    eye = np.array(cam.location)
    for f in range(1, frames + 1):
        a = math.radians(ORBIT_DEG * (f - 1))
        d = eye - target
        p = target + np.array((d[0] * math.cos(a) - d[1] * math.sin(a),
                               d[0] * math.sin(a) + d[1] * math.cos(a), d[2]))
        cam.location = tuple(p)
        cam.rotation_euler = S.look(tuple(p), tuple(target))
        cam.keyframe_insert("location", frame=f)
        cam.keyframe_insert("rotation_euler", frame=f)
    s.frame_start, s.frame_end = 1, frames
    return s


def roll_shot(size: int, frames: int):
    """The interior, an orange sphere rolling across the floor by ROLL a frame."""
    s = S.interior(size)
    mat, _ = S.material("ball", "ShaderNodeBsdfPrincipled",
                        **{"Base Color": (0.9, 0.4, 0.1, 1.0), "Roughness": 0.4})
    ball = S.sphere(0.3, (-1.2, -0.6, 0.3), mat=mat)
    for f in range(1, frames + 1):
        ball.location = (-1.2 + ROLL * (f - 1), -0.6, 0.3)
        ball.keyframe_insert("location", frame=f)
    s.frame_start, s.frame_end = 1, frames
    return s


MOVING = {"orbit": orbit_shot, "roll": roll_shot}


def cel_bands(image: np.ndarray, depth: np.ndarray) -> tuple[tuple, tuple]:
    """cel's auto rule (styles/cel.py, `tone.band_levels`) read off an EEVEE frame: the thresholds
    are the brightness quantiles 1/K..(K-1)/K and the levels `band_levels` of the brightness
    u = (r + g + b) / 3 of the pixels that see a surface (styletrace reads its first hits).

    Args:
        image: H x W x 3 linear frame. depth: H x W, its Depth pass (no surface: >= 1e9).

    Returns:
        (thresholds, levels): CEL_BANDS - 1 and CEL_BANDS increasing floats.
    """
    k = CEL_BANDS
    u = image[..., :3].mean(axis=-1)[depth < 1e9]

    def quantile(qs):
        return [float(x) for x in np.quantile(u, qs)]

    return increasing(quantile([i / k for i in range(1, k)])), increasing(band_levels(quantile, k))


def toon_materials(thresholds, levels) -> None:
    """Every material's surface through Shader to RGB and cel's bands (EEVEE only).

    The shaded colour c (Shader to RGB) has brightness u = (r + g + b) / 3; a ColorRamp with
    CONSTANT interpolation, on u / scale, gives m_j, the level of u's band (stops at the
    thresholds / scale, scale twice the last threshold so that every stop is inside [0, 1]); the
    surface becomes an Emission of c m_j / u (cel's `apply`; black where u = 0, where cel gives
    grey m_0). Lights and the world are left as they are.

    Args:
        thresholds, levels: cel's (`cel_bands`).
    """
    scale = 2.0 * thresholds[-1]
    for mat in bpy.data.materials:
        nt = mat.node_tree
        out = next((n for n in nt.nodes if n.bl_idname == "ShaderNodeOutputMaterial"), None)
        if out is None or not out.inputs["Surface"].links:
            continue
        shader = out.inputs["Surface"].links[0].from_socket
        to_rgb = nt.nodes.new("ShaderNodeShaderToRGB")
        nt.links.new(shader, to_rgb.inputs["Shader"])
        u = nt.nodes.new("ShaderNodeVectorMath")
        u.operation = "DOT_PRODUCT"
        u.inputs[1].default_value = (1 / 3, 1 / 3, 1 / 3)
        nt.links.new(to_rgb.outputs["Color"], u.inputs[0])
        fac = nt.nodes.new("ShaderNodeMath")
        fac.operation = "DIVIDE"
        nt.links.new(u.outputs["Value"], fac.inputs[0])
        fac.inputs[1].default_value = scale
        ramp = nt.nodes.new("ShaderNodeValToRGB")
        ramp.color_ramp.interpolation = "CONSTANT"
        stops = ramp.color_ramp.elements
        while len(stops) < len(levels):
            stops.new(1.0)
        for stop, at, m in zip(stops, (0.0, *(x / scale for x in thresholds)), levels):
            stop.position, stop.color = at, (m, m, m, 1.0)
        nt.links.new(fac.outputs["Value"], ramp.inputs["Fac"])
        safe = nt.nodes.new("ShaderNodeMath")
        safe.operation = "MAXIMUM"
        nt.links.new(u.outputs["Value"], safe.inputs[0])
        safe.inputs[1].default_value = 1e-6
        gain = nt.nodes.new("ShaderNodeMath")
        gain.operation = "DIVIDE"
        nt.links.new(ramp.outputs["Color"], gain.inputs[0])  # the ramp's grey: its value is m_j
        nt.links.new(safe.outputs["Value"], gain.inputs[1])
        banded = nt.nodes.new("ShaderNodeVectorMath")
        banded.operation = "SCALE"
        nt.links.new(to_rgb.outputs["Color"], banded.inputs["Vector"])
        nt.links.new(gain.outputs["Value"], banded.inputs["Scale"])
        emit = nt.nodes.new("ShaderNodeEmission")
        nt.links.new(banded.outputs["Vector"], emit.inputs["Color"])
        emit.inputs["Strength"].default_value = 1.0
        nt.links.new(emit.outputs["Emission"], out.inputs["Surface"])


def eevee(s, folder: str, bands=None) -> float:
    """Switch `s` to EEVEE (Blender 5.0's EEVEE Next, its defaults) with its Depth pass, with the
    toon materials where `bands` is given (`toon_materials`), and render frame 1 once before the
    timed animation, so that a scene's first render, which may differ in cost from the later
    ones (shader compilation), is timed apart. Measured here with software OpenGL it is the other
    way round: the first render took 4 s at 64 x 64 and each later one, frame 1 again included,
    about 30 s (the same image).

    Returns:
        The seconds of that first render.
    """
    s.render.engine = "BLENDER_EEVEE"
    s.view_layers[0].use_pass_z = True
    if bands is not None:
        toon_materials(*bands)
    s.frame_set(1)
    s.render.filepath = os.path.join(folder, "first")
    start = time.perf_counter()
    bpy.ops.render.render(write_still=True)
    return time.perf_counter() - start


def moving_frames(name: str, size: int, frames: int, folder: str, engine: str,
                  style: str | None = None, reuse: bool = False, samples: int | None = None,
                  bands=None, seed: int = SEED):
    """A moving shot rendered by Render Animation with its Vector and Depth passes:
    ([(image, vector, depth)], seconds per frame, EEVEE's first render's seconds or None) (depth:
    `depth_of`). styletrace with `samples` where given (else
    the add-on's default); EEVEE (`eevee`) with the toon materials where `bands` is given.

    Every engine here writes Blender's Vector convention in X, Y (`warped`; EEVEE's checked: module
    doc)."""
    s = MOVING[name](size, frames)
    layer = s.view_layers[0]
    layer.use_pass_vector, layer.use_pass_z = True, True
    s.render.engine = engine
    first = None
    if engine == "CYCLES":
        c = s.cycles
        c.device, c.samples, c.seed, c.use_animated_seed = "CPU", 16, SEED, True
        c.use_denoising, c.denoiser = True, "OPENIMAGEDENOISE"
    elif engine == "BLENDER_EEVEE":
        first = eevee(s, folder, bands)
    else:
        st = s.styletrace
        st.style, st.seed, st.temporal_reuse = style, seed, reuse
        if samples is not None:
            st.samples = samples
    s.render.filepath = os.path.join(folder, "frame_####")
    start = time.perf_counter()
    bpy.ops.render.render(animation=True)
    seconds = (time.perf_counter() - start) / frames
    out = []
    for f in range(1, frames + 1):
        p = S.read_exr(s.render.frame_path(frame=f))
        out.append((p["Combined"][..., :3], p["Vector"], depth_of(s, p)))
    return out, seconds, first


def depth_of(s, passes: dict) -> np.ndarray:
    """The Depth pass, H x W, where no surface is seen >= 1e9 as Cycles and styletrace write it
    (EEVEE writes about the camera's clip end there)."""
    depth = np.asarray(passes["Depth"], dtype=np.float64)
    depth = depth.reshape(depth.shape[:2])
    if s.render.engine == "BLENDER_EEVEE":
        depth = np.where(depth >= 0.999 * s.camera.data.clip_end, 1e10, depth)
    return depth


def eevee_still(size: int, frames: int, folder: str, bands=None):
    """The still shot by EEVEE (`eevee`): (frames, seconds per frame, frame 1's depth (`depth_of`),
    the first render's seconds)."""
    s = scene(size, frames)
    first = eevee(s, folder, bands)
    images, seconds = animate(s, folder, frames)
    return images, seconds, depth_of(s, S.read_exr(s.render.frame_path(frame=1))), first


def moving_rows(name: str, size: int, frames: int, tmp: str, eevee_rows: bool,
                floor: bool, eevee_frames: int = EEVEE_FRAMES) -> list[dict]:
    """A moving shot's rows: Cycles; EEVEE and EEVEE toon (its bands from EEVEE's own frame 1,
    `cel_bands`, over `eevee_frames` frames) where `eevee_rows`; each style without and with
    reuse; each style's expected frames (`clean_warp_error` of two renders at Samples
    REF_SAMPLES_MOVING, reuse off) where `floor`.

    Returns:
        [{shot, name, style, reuse (None: no such setting), converged, warp, tone, seconds,
        first (EEVEE's first render's seconds, else None)}]: warp and tone are `warp_error`'s
        without and with the blur.
    """
    def row(label, style, reuse, converged, result):
        fr, secs, first = result
        return {"shot": name, "name": label, "style": style, "reuse": reuse,
                "converged": converged, "warp": warp_error(fr), "tone": warp_error(fr, tone=True),
                "seconds": secs, "first": first}

    folder = os.path.join(tmp, name)
    say(name, "Cycles")
    out = [row("Cycles", "Cycles", None, False,
               moving_frames(name, size, frames, folder + "_cy", "CYCLES"))]
    if eevee_rows:
        say(name, "EEVEE")
        plain = moving_frames(name, size, eevee_frames, folder + "_eevee", "BLENDER_EEVEE")
        out.append(row(EEVEE_NAME, "EEVEE", None, False, plain))
        say(name, "EEVEE toon")
        bands = cel_bands(plain[0][0][0], plain[0][0][2])
        out.append(row(TOON_NAME, "EEVEE toon", None, False,
                       moving_frames(name, size, eevee_frames, folder + "_toon",
                                     "BLENDER_EEVEE",
                                     bands=bands)))
        out[-1]["bands"] = bands
    for style in STYLES:
        for reuse in (False, True):
            say(name, style, "reuse" if reuse else "no reuse")
            out.append(row(f"styletrace {style}", style, reuse, False,
                           moving_frames(name, size, frames, f"{folder}_{style}_{reuse}",
                                         "STYLETRACE", style, reuse)))
    if floor:
        for style in STYLES:
            say(name, style, "converged")
            renders = [moving_frames(name, size, frames, f"{folder}_{style}_converged_{seed}",
                                     "STYLETRACE", style, False, REF_SAMPLES_MOVING, seed=seed)
                       for seed in FLOOR_SEEDS]
            fr = [r[0] for r in renders]
            out.append({"shot": name, "style": style, "reuse": False, "converged": True,
                        "name": f"styletrace {style}, expected frames (Samples "
                                f"{REF_SAMPLES_MOVING}, two seeds)",
                        "warp": clean_warp_error(*fr), "tone": clean_warp_error(*fr, tone=True),
                        "seconds": float(np.mean([r[1] for r in renders])), "first": None})
    return out


def references(size, style, folder):
    out = []
    for seed in REF_SEEDS:
        s = scene(size, 1)
        s.render.engine = "STYLETRACE"
        st = s.styletrace
        st.style, st.seed, st.samples = style, seed, REF_SAMPLES
        path = os.path.join(folder, f"ref_{style}_{seed}")
        s.render.filepath = path
        bpy.ops.render.render(write_still=True)
        out.append(S.read_exr(path + ".exr")["Combined"][..., :3])
    return out


def summary(images) -> dict:
    pairs = [flicker(a, b) for a, b in zip(images, images[1:])]
    return {"rel": float(np.mean([p[0] for p in pairs])),
            "abs": float(np.mean([p[1] for p in pairs])),
            "rel_pairs": [p[0] for p in pairs]}


def figure(plain, reused, path: str) -> None:
    from PIL import Image
    rows = []
    for frames in (plain, reused):
        a, b = srgb(frames[-2]), srgb(frames[-1])
        diff = np.clip(np.abs(a - b).max(axis=-1, keepdims=True) * 4.0, 0, 1).repeat(3, -1)
        rows.append(np.concatenate([a, b, diff], axis=1))
    img = (np.concatenate(rows, axis=0) * 255 + 0.5).astype(np.uint8)
    tmp = path + ".tmp.png"
    Image.fromarray(img).save(tmp)
    os.replace(tmp, path)


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--size", type=int, default=None)
    p.add_argument("--frames", type=int, default=None)
    p.add_argument("--quick", action="store_true", help="a smoke run (48 x 48, 3 frames)")
    p.add_argument("--no-write", action="store_true")
    p.add_argument("--no-figure", action="store_true")
    p.add_argument("--no-moving", action="store_true", help="leave out the moving shots")
    p.add_argument("--moving-size", type=int, default=None, help="the moving shots' side")
    p.add_argument("--no-eevee", action="store_true", help="leave out EEVEE's rows")
    p.add_argument("--no-floor", action="store_true",
                   help="leave out the moving shots' converged rows (Samples REF_SAMPLES_MOVING)")
    p.add_argument("--eevee-frames", type=int, default=None,
                   help=f"EEVEE's frames (default {EEVEE_FRAMES}, at most --frames)")
    a = p.parse_args()
    size = a.size or (48 if a.quick else 256)
    frames = a.frames or (3 if a.quick else 8)
    eevee_frames = min(frames, a.eevee_frames or EEVEE_FRAMES)
    addon.register()
    rows, figure_frames = [], {}
    with tempfile.TemporaryDirectory() as tmp:
        say("Cycles")
        cy, cy_s = cycles_frames(size, frames, os.path.join(tmp, "cycles"))
        cycles_row = {"name": "Cycles, 16 samples, OIDN, animated seed", **summary(cy),
                      "seconds": cy_s, "errors": None}
        others = [cycles_row]
        if not a.no_eevee:
            say("EEVEE")
            folder = os.path.join(tmp, "eevee")
            imgs, secs, depth, first = eevee_still(size, eevee_frames, folder)
            ee = bpy.context.scene.eevee
            others.append({"name": EEVEE_NAME, **summary(imgs), "seconds": secs, "first": first,
                           "samples": ee.taa_render_samples})
            say("EEVEE toon")
            bands = cel_bands(imgs[0], depth)
            imgs, secs, _, first = eevee_still(size, eevee_frames, folder + "_toon", bands)
            others.append({"name": TOON_NAME, **summary(imgs), "seconds": secs, "first": first,
                           "bands": bands})
        for style in STYLES + STILL_ONLY:
            say(style, "references")
            r1, r2 = references(size, style, tmp)
            timed = {False: [], True: []}
            for run in range(TIMINGS):  # off, on, off, on: the cost from each one's fastest
                for reuse in (False, True):
                    say(style, "reuse" if reuse else "no reuse", f"(run {run + 1})")
                    imgs, secs = styletrace_frames(size, frames, style, reuse,
                                                   os.path.join(tmp, f"{style}_{reuse}_{run}"))
                    timed[reuse].append(secs)
                    if run == 0:
                        rows.append({"style": style, "reuse": reuse, **summary(imgs),
                                     "errors": [error(i, r1, r2) for i in imgs],
                                     "first": imgs[0]})
                        if style == "cel":
                            figure_frames[reuse] = imgs
            for r in rows[-2:]:
                r["seconds"] = min(timed[r["reuse"]])
    moving = []
    msize = a.moving_size or (32 if a.quick else 128)
    if not a.no_moving:
        with tempfile.TemporaryDirectory() as tmp:
            for name in MOVING:
                moving += moving_rows(name, msize, frames, tmp, not a.no_eevee, not a.no_floor,
                                      eevee_frames)
    by = {(r["style"], r["reuse"]): r for r in rows}
    for style in STYLES + STILL_ONLY:  # the first frame has no earlier frame: unchanged
        off, on = by[(style, False)]["first"], by[(style, True)]["first"]
        by[(style, True)]["first_diff"] = float(np.abs(off - on).max())
    text = report(rows, others, size, frames) + moving_report(moving, msize, frames)
    print(text)
    if not a.quick and not a.no_write:
        write_section("temporal", text)
    if not a.no_figure and not a.quick:
        figure(figure_frames[False], figure_frames[True],
               os.path.join(os.path.dirname(HERE), "docs", "temporal.png"))


def report(rows, others, size, frames) -> str:
    """The still shot's table: `others` (Cycles first, then EEVEE's rows if any), then styletrace's
    `rows` (module doc)."""
    lines = [
        "## Animation: a still shot's flicker, with and without temporal reuse",
        "",
        f"`benchmarks/temporal.py`: the tests' interior lit through a window, {size} x {size}, "
        f"Render Animation of frames 1 to {frames}, nothing animated; styletrace at the add-on's "
        "defaults (Samples 16, Denoise auto, a seed per frame) with Temporal reuse off (the frames "
        "as before) and on (docs/temporal.md); Cycles at 16 samples with OIDN and an animated "
        "seed. "
        "Flicker: the mean over consecutive pairs of the share of pixels whose display-space "
        "brightness changes by more than 10% of the larger (below 0.05 as 0.05), and of the share "
        "whose display-space channels change by more than 0.1. Error of frame k: against two "
        f"renders of the same defaults at Samples {REF_SAMPLES} (their noise cancels), as PSNR. "
        "Temporal reuse's constants were chosen on the Cornell box, not on this scene. "
        + machine_description(),
        "",
        "| renderer, style | temporal reuse | pixels changing > 10% per frame | display change > "
        "0.1 | per pair (> 10%) | PSNR of frames 1..k | seconds a frame | goal |",
        "|---|---|---|---|---|---|---|---|",
    ]
    cy = others[0]
    for o in others:
        note = "-" if o.get("first") is None else first_note(o)
        lines.append(f"| {o['name']} | - | {o['rel']:.2%} | {o['abs']:.2%} | "
                     f"{' / '.join(f'{v:.1%}' for v in o['rel_pairs'])} | - | "
                     f"{o['seconds']:.2f} | {note} |")
    by = {(r["style"], r["reuse"]): r for r in rows}
    for r in rows:
        goal = "-"
        if r["reuse"]:
            limit = GOALS.get(r["style"], cy["rel"])
            met = r["rel"] <= limit
            cost = r["seconds"] / by[(r["style"], False)]["seconds"]
            goal = (f"{'met' if met else 'NOT met'} (<= {limit:.1%}); cost {cost:.2f}x; first "
                    f"frame's largest difference {r['first_diff']:.1e}")
        lines.append(
            f"| styletrace {r['style']} | {'on' if r['reuse'] else 'off'} | {r['rel']:.2%} | "
            f"{r['abs']:.2%} | {' / '.join(f'{v:.1%}' for v in r['rel_pairs'])} | "
            f"{' '.join(psnr(e) for e in r['errors'])} | {r['seconds']:.2f} | {goal} |")
    bands = next((o["bands"] for o in others if "bands" in o), None)
    if bands is not None:
        lines += ["", eevee_note(others[1]["samples"], bands)]
    lines += ["", "![Two consecutive cel frames and their difference (x4), without reuse (top) "
              "and with it (bottom)](docs/temporal.png)", ""]
    return "\n".join(lines)


def first_note(row: dict) -> str:
    return f"- (a render of frame 1 before the animation: {row['first']:.1f} s)"


def eevee_note(samples: int, bands) -> str:
    """What EEVEE's rows are: its Render Samples, the still shot's bands."""
    t, m = bands
    return (f"{EEVEE_NAME}: Render Samples {samples}, no motion blur, after one render of frame 1 "
            f"timed apart (in the goal column). {TOON_NAME}: every material's surface through "
            "Shader to RGB, then a ColorRamp with constant interpolation on its brightness "
            "u = (r + g + b) / 3 into "
            "an Emission of colour x level / u (black where u = 0; cel: grey), as styletrace's cel "
            "with its defaults: "
            f"{CEL_BANDS} bands, thresholds the brightness quantiles 1/{CEL_BANDS}.. of the "
            "pixels that see a surface in EEVEE's own frame 1 and levels by cel's auto rule "
            f"(here thresholds {', '.join(f'{x:.3g}' for x in t)}, levels "
            f"{', '.join(f'{x:.3g}' for x in m)}); the sun, sky and lamps as they are. No light "
            "probe volume is baked (EEVEE's defaults): its indirect light inside the room comes "
            "from the world's probe, so the interior is lighter and bluer than Cycles' and "
            "styletrace's.")


def moving_report(rows: list, size: int, frames: int) -> str:
    """The moving shots' table and goals (module doc)."""
    if not rows:
        return ""
    lines = ["", "### Moving shots: warping error", "",
             f"{size} x {size}, {frames} frames: the still life with the camera turning "
             f"{ORBIT_DEG} degrees a frame about its target (orbit), the interior with a sphere "
             f"rolling {ROLL} a frame (roll); the same renderers and defaults. Warping error x "
             "1e-3 (display space; lower is steadier), and on the tone: both frames blurred over "
             f"{TONE} pixels (hatching's line spacing; its pattern stays on the screen by design, "
             "so its goal compares its tone with identity's tone). Expected frames: each style"
             f" rendered twice at Samples {REF_SAMPLES_MOVING} (reuse off) with two other "
             "seeds, and the mean of (b1 - W a1)(b2 - W a2) over the pixels seen in both, so "
             "that the noise cancels: the warping error of the frames' expected images, the "
             "floor of any renderer that converges to the right frames (the lighting that "
             "changes, and the warp's resampling of sharp edges); a goal row's 'floor' is that"
             " row's ratio to identity's.", "",
             "| shot | renderer, style | temporal reuse | warping error (x 1e-3) | on the tone | "
             "seconds a frame | goal |", "|---|---|---|---|---|---|---|"]
    key = {(r["shot"], r["style"], r["reuse"], r["converged"]): r for r in rows}
    for r in rows:
        goal = "-"
        measure = "tone" if r["style"] == "hatching" else "warp"
        if r["reuse"] and r["style"] != "identity":
            own = r[measure]
            before_v = key[(r["shot"], r["style"], False, False)][measure]
            ident = key[(r["shot"], "identity", True, False)][measure]
            ok = own <= 1.2 * ident and own <= 0.5 * before_v
            which = "identity's tone" if measure == "tone" else "identity's"
            today = key[(r["shot"], "identity", False, False)][measure]
            goal = (f"{'met' if ok else 'NOT met'}: {own / ident:.2f}x {which} "
                    f"({own / today:.2f}x without reuse), {own / before_v:.2f}x its own without "
                    "reuse")
            floor = key.get((r["shot"], r["style"], False, True))
            if floor is not None:
                base = key[(r["shot"], "identity", False, True)][measure]
                goal += (f"; floor: {floor[measure] / base:.2f}x {which}" if base > 0 else
                         "; floor: - (identity's at the noise's level)")
        elif r["reuse"]:
            before = key[(r["shot"], "identity", False, False)]["warp"]
            goal = f"{r['warp'] / before:.2f}x without reuse"
        elif r.get("first") is not None:
            goal = first_note(r)
            if "bands" in r:
                goal += ("; thresholds " + ", ".join(f"{x:.3g}" for x in r["bands"][0])
                         + ", levels " + ", ".join(f"{x:.3g}" for x in r["bands"][1]))
        reuse = "-" if r["reuse"] is None else ("on" if r["reuse"] else "off")
        lines.append(f"| {r['shot']} | {r['name']} | {reuse} | {1e3 * r['warp']:.3f} | "
                     f"{1e3 * r['tone']:.3f} | {r['seconds']:.2f} | {goal} |")
    return "\n".join(lines) + "\n"


if __name__ == "__main__":
    main()
