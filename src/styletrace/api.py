"""The Python API: load a scene, build the `stylized` integrator, render in passes.

    import styletrace
    img = styletrace.render("cornell-box", style="cel", spp=16, inner=8)   # H x W x 3 float32, linear

Large renders run as several passes of at most `LANES_PER_PASS` camera samples, so memory stays
bounded whatever spp and inner sample counts are; each pass has its own seed derived from `seed`,
so the same seed reproduces the same image exactly. The split into passes depends only on the image
size and the sample counts (`pass_size`), never on measured time, because a different split draws
different samples. An image of more than `LANES_PER_PASS` pixels is rendered in tiles (crop windows
of one fixed size), and the running sum is one float32 image; `check_memory` refuses up front an
image whose buffers cannot fit.
"""
from __future__ import annotations

import contextlib
import math
import os
import re
import warnings
from dataclasses import dataclass
from typing import Any, Callable, Iterator

from .jit import backend, no_collection
from .runtime import init

backend()  # Dr.Jit picks its libLLVM when first imported: choose it (and the variant) before that

import mitsuba as mi  # noqa: E402
import numpy as np  # noqa: E402

from . import scene_file  # noqa: E402
from .arguments import check_passes_args, check_render_args, check_scene, scene_problem  # noqa: E402
from .errors import SceneError, UsageError  # noqa: E402
from .images import PIXEL_FORMATS, save_safely, write_image  # noqa: E402
from .normals import canonical_normals as _canonical  # noqa: E402
from .plugins.integrator import StylizedIntegrator  # noqa: E402
from .plugins.scene_defaults import resolve as resolve_defaults  # noqa: E402
from .plugins.scenes import BUILTIN, DEFAULT  # noqa: E402

#: Camera samples per pass: bounds the memory of the megakernel's state (~ a few hundred bytes each).
LANES_PER_PASS = 1 << 20
#: Width of a tile when an image has more than LANES_PER_PASS pixels (a tile is 1024 x 1024 then).
TILE_SIDE = 1024
#: Host memory per lane of a pass (the film's block, the output, the sampler), for the up-front estimate;
#: a 1024 x 1024 pass at 1 spp measured about 50 MB more than a 256 x 256 one (BENCHMARKS.md, memory).
LANE_BYTES = 256


def first_line(exc: BaseException) -> str:
    text = str(exc).strip()
    lines = [ln.strip() for ln in text.splitlines() if ln.strip()]
    # Mitsuba prefixes the real cause with context lines; the last line is the most specific.
    return lines[-1] if lines else type(exc).__name__


def _size(width, height, keys=("width", "height")) -> dict[str, int]:
    """The given image size as keyword arguments, leaving out what was not given."""
    return {k: v for k, v in zip(keys, (width, height)) if v}


def scene_dict(name: str, width: int | None = None, height: int | None = None) -> dict[str, Any]:
    if name not in BUILTIN:
        raise SceneError(f"unknown built-in scene '{name}': available are {', '.join(sorted(BUILTIN))}")
    return BUILTIN[name](**_size(width, height))


def canonical_normals(scene: mi.Scene) -> mi.Scene:
    """The scene with its computed vertex normals made the same in every process (`normals`): the same seed
    then gives the same image to the bit. Scenes load on all of Dr.Jit's threads (one thread deadlocks
    Mitsuba's OpenEXR reader)."""
    _canonical(scene)
    return scene


def load_scene(scene: Any = None, width: int | None = None, height: int | None = None,
               defines: dict[str, Any] | None = None) -> mi.Scene:
    """A built-in name, a Mitsuba XML path, a scene dict or an mi.Scene -> mi.Scene.

    For an XML file, `defines` are the values of its `<default>` parameters (as `mitsuba -D name=value`),
    and width/height resize its film; an integrator type Mitsuba does not know is replaced, with a
    `SceneWarning` (see `scene_file`)."""
    init()
    if scene is None:
        scene = DEFAULT
    if defines and not (isinstance(scene, (str, os.PathLike)) and os.fspath(scene) not in BUILTIN):
        raise SceneError("defines apply to XML scene files (their <default> parameters) only")
    if isinstance(scene, mi.Scene):
        check_scene(scene, "the mi.Scene")
        if width or height:
            size = scene.sensors()[0].film().size()
            if (width and width != size[0]) or (height and height != size[1]):
                raise SceneError("width/height cannot change an already loaded mi.Scene; pass a dict or file")
        return scene
    if isinstance(scene, dict):
        if width or height:
            raise SceneError("width/height apply to built-in scenes and XML files; set the film size in the dict")
        try:
            loaded = mi.load_dict(scene)
        except Exception as exc:  # Mitsuba raises RuntimeError with several context lines
            raise SceneError(f"cannot load scene dict: {first_line(exc)}") from None
        problem = scene_problem(loaded, "the scene dict")
        if problem is not None:
            del loaded  # see arguments.scene_problem: a refused scene must not outlive this call
            raise SceneError(problem)
        return canonical_normals(loaded)
    if not isinstance(scene, (str, os.PathLike)):
        raise SceneError(f"bad scene {scene!r}: expected a built-in name ({', '.join(sorted(BUILTIN))}), an XML "
                         f"path, a scene dict or an mi.Scene")
    name = os.fspath(scene)
    if name in BUILTIN:
        try:
            return canonical_normals(mi.load_dict(scene_dict(name, width, height)))
        except Exception as exc:
            raise SceneError(f"cannot load built-in scene '{name}': {first_line(exc)}") from None
    if not name.lower().endswith(".xml") and not os.path.exists(name):
        raise SceneError(f"unknown scene '{name}': expected a built-in scene ({', '.join(sorted(BUILTIN))}) "
                         f"or a Mitsuba XML file")
    if not os.path.isfile(name):
        raise SceneError(f"scene file '{name}' does not exist")
    try:
        loaded, notes = scene_file.load(name, width, height, defines)
    except SceneError:
        raise
    except Exception as exc:
        if "unused parameters" in str(exc):  # Mitsuba lists them as "- $name=value"
            unused = ", ".join(re.findall(r"\$(\w+)=", str(exc)))
            raise SceneError(f"scene file '{name}' uses no parameter {unused}: -D/defines set only the file's "
                             f"$parameters (its <default> names)") from None
        raise SceneError(f"cannot load scene file '{name}': {first_line(exc)}") from None
    problem = scene_problem(loaded, f"scene file '{name}'")
    if problem is not None:
        del loaded  # see arguments.scene_problem: a refused scene must not outlive this call
        raise SceneError(problem)
    for note in notes:
        warnings.warn(note, SceneWarning, stacklevel=2)
    return canonical_normals(loaded)


class SceneWarning(UserWarning):
    """A scene was changed to render (an unknown integrator replaced); the message names what changed."""


def carried_settings(scene: mi.Scene) -> dict[str, Any]:
    """The settings a scene's own Mitsuba integrator (path, volpath, prb, direct, ...) shares with `stylized`:
    max_depth, rr_depth and hide_emitters, as Mitsuba resolved them (defaults and $parameters applied).
    Mitsuba exposes hide_emitters as a method and the depths only in the integrator's description
    (`PathIntegrator[max_depth = 6, rr_depth = 5]`); `direct` is emission plus direct light, max_depth 2.
    Empty for a `stylized` integrator (its own values are used whole) or none."""
    own = scene.integrator()
    if own is None or isinstance(own, StylizedIntegrator):
        return {}
    text = str(own)
    out: dict[str, Any] = {}
    for key in ("max_depth", "rr_depth"):
        found = re.search(rf"\b{key}\s*=\s*(-?\d+)", text)  # ptracer prints -1, path 2^32 - 1
        if found:
            value = int(found.group(1))
            out[key] = -1 if value >= 2 ** 32 - 1 else value  # Mitsuba stores -1 (unbounded) as UInt32
    if text.startswith("DirectIntegrator"):
        out["max_depth"] = 2
    # a read-only property of Mitsuba's SamplingIntegrators; its AdjointIntegrator binding (ptracer) has none
    if getattr(own, "hide_emitters", False):
        out["hide_emitters"] = True
    return out


def film_format(scene: mi.Scene) -> str:
    """The pixel format of the scene's film as Mitsuba develops it ('rgb', 'rgba', 'y', 'ya', 'xyz', 'xyza'):
    the kernel computes RGB radiance and the film converts it (luminance Y, CIE XYZ, alpha coverage)."""
    found = re.search(r"pixel_format\s*=\s*(\w+)", str(scene.sensors()[0].film()))
    name = found.group(1).lower() if found else "rgb"
    if name not in PIXEL_FORMATS:
        raise SceneError(f"the film's pixel format {name!r} cannot be written: expected one of "
                         f"{', '.join(sorted(set(PIXEL_FORMATS)))}")
    return name


def scene_spp(scene: mi.Scene) -> int:
    """The scene's own camera samples per pixel: its sampler's sample_count."""
    return int(scene.sensors()[0].sampler().sample_count())


def make_integrator(style: str | None = None, inner: Any = None, estimator: str | None = None,
                    **params: Any) -> StylizedIntegrator:
    """A `stylized` integrator. Integrator properties (stylize, stylize_depth, max_depth, rr_depth) and the
    style's parameters go in **params under their names; what is not given takes the default of
    `plugins.settings` (`inner`: the style's own count, or one per level: (8, 4))."""
    given = {"style": style, "inner_samples": inner, "estimator": estimator, **params}
    return make_integrator_from({k: v for k, v in given.items() if v is not None})


def make_integrator_from(values: dict[str, Any]) -> StylizedIntegrator:
    """A `stylized` integrator from its property values (style, style parameters, inner_samples, ...)."""
    init()
    return StylizedIntegrator.from_values(values)


def pass_seed(seed: int, index: int) -> int:
    """Seed of pass `index`: distinct passes and distinct user seeds get unrelated sample streams."""
    return (seed * 0x9E3779B1 + index * 0x85EBCA6B + 0x27D4EB2F) & 0xFFFFFFFF


def expansion_seed(seed: int, tile: int) -> int:
    """Seed of the expansion pass of tile `tile` (`StylizedIntegrator.prepare_expansion`): pass_seed's stream at
    indices from 2^31 on, which no render reaches, so it differs from every pass seed of the same render."""
    return pass_seed(seed, (1 << 31) + tile)


@dataclass(frozen=True)
class Tile:
    """One crop window of the film (all tiles of a render share one size, so the kernel compiles once per
    offset and not per size) and the part of it that is new: edge tiles are shifted inwards to stay inside
    the film, and the pixels they share with their neighbour are dropped."""
    offset: tuple[int, int]   # x, y of the crop window
    size: tuple[int, int]     # width, height of the crop window
    keep: tuple[slice, slice]  # rows, columns of the rendered tile that are new
    dest: tuple[slice, slice]  # where those go in the image


def _axis(length: int, tile: int) -> list[tuple[int, slice, slice]]:
    out, start = [], 0
    while start < length:
        offset = min(start, length - tile)
        out.append((offset, slice(start - offset, tile), slice(start, offset + tile)))
        start = offset + tile
    return out


def tiles(width: int, height: int, max_pixels: int | None = None) -> list[Tile]:
    """The film as one tile if it has at most `max_pixels` pixels, else as tiles of TILE_SIDE columns
    (or the width, if narrower) and as many rows as fit into `max_pixels` (default LANES_PER_PASS)."""
    max_pixels = max_pixels or LANES_PER_PASS
    if width * height <= max_pixels:
        return [Tile((0, 0), (width, height), (slice(None), slice(None)), (slice(None), slice(None)))]
    tw = min(width, TILE_SIDE, max_pixels)
    th = min(height, max(1, max_pixels // tw))
    return [Tile((x, y), (tw, th), (ky, kx), (dy, dx))
            for y, ky, dy in _axis(height, th) for x, kx, dx in _axis(width, tw)]


def memory_needed(width: int, height: int, ext: str = ".exr") -> int:
    """Bytes of host memory a render of this size needs at its peak, while the file is written: the
    float32 accumulator, the averaged image, Mitsuba's bitmap of it, and the encoded file (up to twice in
    the growing memory stream, once more as bytes), plus the lanes of one pass."""
    image = width * height * 3 * 4
    encoded = width * height * 3 * (1 if ext == ".png" else 4)
    return 3 * image + 3 * encoded + LANE_BYTES * LANES_PER_PASS


def memory_available() -> int | None:
    """MemAvailable of /proc/meminfo, or less if an address-space limit is set; None where unknown."""
    import resource
    limits = []
    try:
        with open("/proc/meminfo") as f:
            for line in f:
                if line.startswith("MemAvailable:"):
                    limits.append(int(line.split()[1]) * 1024)
    except (OSError, ValueError):
        pass
    soft = resource.getrlimit(resource.RLIMIT_AS)[0]
    if soft not in (resource.RLIM_INFINITY, -1):
        limits.append(soft)
    return min(limits) if limits else None


def check_memory(width: int, height: int, ext: str = ".exr") -> None:
    """Refuse up front (UsageError) an image whose buffers cannot fit into the memory there is."""
    need, have = memory_needed(width, height, ext), memory_available()
    if width >= 1 << 31 or height >= 1 << 31 or (have is not None and need > have):
        have_txt = f"{have / 2**30:.1f} GiB available" if have is not None else "too large"
        raise UsageError(f"image {width}x{height} is too large: it needs about {need / 2**30:.1f} GiB of "
                         f"memory ({have_txt}); render a smaller --width/--height")


class Progress:
    """State after a pass: `spp_done` is what every pixel has at least (tiles of a pass under way may
    have one more pass); `image` is the average of the finished passes, computed when asked for."""

    def __init__(self, spp_done: int, spp_total: int, total: np.ndarray, counts: np.ndarray, layout: list[Tile],
                 channels: int | None = None):
        self.spp_done, self.spp_total = spp_done, spp_total
        self._total, self._counts, self._tiles = total, counts, layout
        #: the image's channels in `total`; the error AOVs' sums follow them (`AOV_NAMES`)
        self._channels = total.shape[-1] if channels is None else channels

    def _mean(self) -> np.ndarray:
        out = np.empty_like(self._total)
        for tile, n in zip(self._tiles, self._counts):
            np.divide(self._total[tile.dest], max(int(n), 1), out=out[tile.dest])
        return out

    @property
    def image(self) -> np.ndarray:
        if self._channels == self._total.shape[-1]:
            return self._mean()
        return np.ascontiguousarray(self._mean()[..., :self._channels])

    @property
    def aovs(self) -> dict[str, np.ndarray] | None:
        """The error AOVs of an integrator with `aovs=True` (else None), float32 H x W (x 3):
        `variance`: the variance of each pixel's estimate (its mean over the camera samples), per RGB channel:
        (mean of the squared samples - squared mean) / (spp - 1), the unbiased sample variance over spp;
        NaN where a pixel has fewer than 2 samples. `bias`: the predicted direct-application bias of Eq. 21,
        g''(<I>_n) s^2 / (2n), at the first stylized vertex, averaged over the pixel's samples (0 where no
        child was drawn). `children`: the children used there, averaged (n for a fixed count)."""
        if self._channels == self._total.shape[-1]:
            return None
        mean = self._mean().astype(np.float64)
        c = self._channels
        counts = np.zeros(mean.shape[:2])
        for tile, n in zip(self._tiles, self._counts):
            counts[tile.dest] = n
        rgb, square = mean[..., :3], mean[..., c:c + 3]
        with np.errstate(divide="ignore", invalid="ignore"):
            var = np.maximum(square - rgb * rgb, 0.0) / (counts[..., None] - 1.0)
        var[counts < 2] = np.nan
        return {"variance": var.astype(np.float32), "bias": mean[..., c + 3].astype(np.float32),
                "children": mean[..., c + 4].astype(np.float32)}


def pass_size(width: int, height: int, spp: int, lanes_per_pass: int = LANES_PER_PASS,
              pass_spp: int | None = None) -> tuple[list[Tile], int]:
    """The tiles and the samples per pixel of one pass. A function of the image size and the counts only,
    never of measured time: the same seed gives the same image on every run."""
    layout = tiles(width, height)
    tw, th = layout[0].size
    per_pass = pass_spp if pass_spp else max(1, lanes_per_pass // (tw * th))
    return layout, max(1, min(spp, per_pass))


def passes(scene: mi.Scene, integrator: mi.Integrator, spp: int, seed: int = 0,
           lanes_per_pass: int = LANES_PER_PASS, pass_spp: int | None = None,
           lock: Any = contextlib.nullcontext()) -> Iterator[Progress]:
    """Render `spp` samples per pixel in passes; yield the running average after each pass.

    An image of more than LANES_PER_PASS pixels is rendered tile by tile (crop windows of the film); a pass
    is then one tile at a time, and every tile gets its passes in turn. The sum of the passes is kept in
    float32, one image's worth of memory. `lock` (a context manager) is held while it is updated, so that
    another thread may read a consistent `Progress.image` meanwhile (the command line's signal watcher).
    A `stylized` integrator with expansion_pass > 0 renders its expansion pass for each tile before the tile's
    first pass (`expansion_seed`: another stream than the passes', the same for the same seed).
    An integrator with `aovs=True` adds its AOV channels (`aov_names`) to the film; they are summed with the
    image and read as `Progress.aovs` (docs/adaptive.md)."""
    check_passes_args(scene, integrator, spp, seed)
    integrator = resolve_defaults(scene, integrator)[0]  # scene-relative 'auto' style values (scene_defaults)
    sensor = scene.sensors()[0]
    film = sensor.film()
    width, height = (int(v) for v in film.crop_size())
    base = tuple(int(v) for v in film.crop_offset())
    check_memory(width, height)
    layout, per_pass = pass_size(width, height, spp, lanes_per_pass, pass_spp)
    params = mi.traverse(sensor) if len(layout) > 1 else None
    channels = len(PIXEL_FORMATS[film_format(scene)])  # the film's own: RGB, Y, XYZ, with alpha or not
    extra = len(integrator.aov_names())  # error AOVs (StylizedIntegrator.aov_names), after the film's channels
    if extra and film_format(scene) not in ("rgb", "rgba"):
        raise UsageError(f"aovs need an rgb or rgba film (the variance is per RGB channel); the scene's film is "
                         f"{film_format(scene)!r}")
    total = np.zeros((height, width, channels + extra), dtype=np.float32)
    counts = np.zeros(len(layout), dtype=np.int64)
    index = 0
    # the expansion pass (expansion_pass > 0): once per tile and render, before the tile's first pass
    expand = getattr(integrator, "prepare_expansion", None)
    if expand is not None:
        integrator.expansion.clear()
    try:
        while counts[-1] < spp:
            for t, tile in enumerate(layout):
                n = min(per_pass, spp - int(counts[t]))
                if params is not None:
                    params["film.crop_offset"] = mi.ScalarPoint2u(base[0] + tile.offset[0], base[1] + tile.offset[1])
                    params["film.crop_size"] = mi.ScalarVector2u(*tile.size)
                    params.update()
                if expand is not None:
                    expand(scene, expansion_seed(seed, t))
                with no_collection():  # recorded and launched with no scene finalised meanwhile (jit.no_collection)
                    img = mi.render(scene, integrator=integrator, spp=n, seed=pass_seed(seed, index))
                    arr = np.asarray(img, dtype=np.float32)[..., :channels + extra]
                with lock:
                    total[tile.dest] += arr[tile.keep] * np.float32(n)
                    counts[t] += n
                del img, arr
                index += 1
                yield Progress(int(counts.min()), spp, total, counts, layout, channels)
    finally:
        if params is not None:  # leave the scene's film as it was
            params["film.crop_offset"] = mi.ScalarPoint2u(*base)
            params["film.crop_size"] = mi.ScalarVector2u(width, height)
            params.update()


def pass_count(scene: mi.Scene, spp: int, lanes_per_pass: int = LANES_PER_PASS, pass_spp: int | None = None) -> int:
    """How many kernel launches `passes` makes (tiles times passes per tile)."""
    size = scene.sensors()[0].film().crop_size()
    layout, per_pass = pass_size(int(size[0]), int(size[1]), spp, lanes_per_pass, pass_spp)
    return len(layout) * math.ceil(spp / per_pass)


def render(scene: Any = None, style: str | None = None, spp: int | None = None, inner: Any = None,
           estimator: str | None = None, seed: int = 0, width: int | None = None, height: int | None = None,
           integrator: mi.Integrator | None = None, callback: Callable[[Progress], None] | None = None,
           defines: dict[str, Any] | None = None, **params: Any) -> np.ndarray:
    """Render with a style; returns float32 H x W x C: linear radiance in the film's pixel format (C = 3 for
    the usual rgb film; 1 for luminance, 4 for rgba, ...; see `film_format`). With `aovs=True` (an integrator
    property) it returns `(image, aovs)`, aovs a dict of the error AOVs (`Progress.aovs`: variance, bias,
    children).

    `scene`: built-in name ('cornell-box', 'dragon', 'furnace'), XML path, scene dict or mi.Scene; `defines`:
    the values of an XML file's `<default>` parameters. `spp`: camera samples per pixel (default: the
    scene sampler's sample_count). Integrator keywords (stylize, stylize_depth, max_depth, rr_depth,
    hide_emitters, lines and the line_* settings of docs/lines.md) and the style's parameters go in
    **params; what is not given takes the scene's own Mitsuba integrator's max_depth/rr_depth/hide_emitters
    (`carried_settings`), else the integrator's defaults (`plugins.settings`: identity, direct, the style's inner count). Pass `integrator=` to use a
    prebuilt one (then style and params are ignored).
    """
    check_render_args(1 if spp is None else spp, seed, integrator)
    sc = load_scene(scene, width, height, defines)
    if integrator is None:
        integrator = make_integrator(style=style, inner=inner, estimator=estimator,
                                     **{**carried_settings(sc), **params})
    spp = scene_spp(sc) if spp is None else spp
    if integrator.aov_names() and spp < 2:
        raise UsageError(f"bad value {spp} for 'spp' with aovs=True: the variance needs at least 2 samples per pixel")
    image = prog = None
    for prog in passes(sc, integrator, spp, seed):
        image = prog.image
        if callback is not None:
            callback(prog)
    if integrator.aov_names():
        return image, prog.aovs
    return image


__all__ = ["render", "load_scene", "carried_settings", "film_format", "scene_spp", "SceneWarning", "make_integrator", "make_integrator_from", "passes", "resolve_defaults", "pass_count", "SceneError",
           "Progress", "StylizedIntegrator", "write_image", "save_safely"]
