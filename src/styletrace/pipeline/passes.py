"""The pass loop: a render as kernel launches of bounded size, tiled, summed into one float32 image.

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
from dataclasses import dataclass
from typing import Any, Iterator

import numpy as np

from styletrace.errors import UsageError
from styletrace.gate import mi
from styletrace.images import PIXEL_FORMATS
from styletrace.jit import no_collection
from styletrace.kernel.launch import LANES_PER_PASS, pass_seed, render_pass, render_pixel_pass
from styletrace.kernel.owen_sobol_sampler import Sequence
from styletrace.scene.arguments import check_passes_args
from styletrace.scene.defaults import ScenePilot
from styletrace.scene.defaults import resolve_defaults as resolve_defaults
from styletrace.scene.loading import film_format

#: Width of a tile when an image has more than LANES_PER_PASS pixels (a tile is 1024 x 1024 then).
TILE_SIDE = 1024
#: Host memory per lane of a pass (the film's block, the output, the sampler), for the up-front
#: estimate; a 1024 x 1024 pass at 1 spp measured about 50 MB more than a 256 x 256 one
#: (BENCHMARKS.md, memory).
LANE_BYTES = 256

def pin_auto_values(
    scene: mi.Scene, integrator: mi.Integrator, pilot: ScenePilot | None = None
) -> tuple[mi.Integrator, str]:
    """Pin an integrator's scene-relative `auto` values: the pipeline's one pinning.

    `resolve.resolve` calls it, and the pass loop for a prebuilt integrator.

    Args:
        scene: the scene the values are measured on.
        integrator: the integrator (anything but `stylized` comes back as it is).
        pilot: the scene-defaults pilot to draw them from (None: a new one; traced only if a value
            needs it).

    Returns:
        (the integrator with its values pinned, the line naming them; '' if none).
    """
    return resolve_defaults(scene, integrator, pilot)


def unit_sequence(seed: int, unit: "Unit") -> Sequence:
    """Where a unit sits in its render's low-discrepancy sequence (`owen_sobol` samplers), keyed
    by the render's first pass seed: a render of one pass draws what `mi.render` with that seed
    draws, and so do the guides of its footprint (`kernel.guides.first_hit`).

    Args:
        seed: the render's seed. unit: the launch.

    Returns:
        kernel.owen_sobol_sampler.Sequence.
    """
    return Sequence(seed=pass_seed(seed, 0), tile=unit.tile, offset=unit.offset)


def expansion_seed(seed: int, tile: int) -> int:
    """Seed of the expansion pass of a tile (`StylizedIntegrator.prepare_expansion`).

    Args:
        seed: the render's seed. tile: the tile's index in the layout.

    Returns:
        pass_seed's stream at index 2^31 + tile, which no render reaches, so it differs from every
        pass seed of the same render.
    """
    return pass_seed(seed, (1 << 31) + tile)


@dataclass(frozen=True)
class Shot:
    """What one render renders, and with which samples: the same shot and split give the same
    image.

    Args:
        scene: the mi.Scene. integrator: its integrator (the `stylized` one, or any other).
        spp: camera samples per pixel. seed: the render's seed (each pass's is `pass_seed`'s).
    """
    scene: Any
    integrator: Any
    spp: int
    seed: int = 0


@dataclass(frozen=True)
class PassSplit:
    """How a render is cut into passes (`pass_size`): a function of the counts only, never of
    measured time, since a different split draws different samples.

    Args:
        lanes_per_pass: camera samples per pass (one kernel launch).
        pass_spp: a fixed number of camera samples per pixel per pass (None, 0: from the lanes).
        grow: each round of passes twice the one before, from pass_spp up to what the lanes
            allow (`rounds`); for samplers whose image does not depend on the split
            (`owen_sobol`: its passes continue one sequence).
    """
    lanes_per_pass: int = LANES_PER_PASS
    pass_spp: int | None = None
    grow: bool = False

    def size(self, width: int, height: int, spp: int) -> tuple[list["Tile"], int]:
        """`pass_size` of this split.

        Args:
            width, height: the film's size. spp: the render's camera samples per pixel.

        Returns:
            (the tiles, the camera samples per pixel of one pass, within [1, spp]).
        """
        return pass_size(width, height, spp, self.lanes_per_pass, self.pass_spp)

    def rounds(self, width: int, height: int, spp: int) -> tuple[list["Tile"], list[int]]:
        """The tiles, and the camera samples per pixel of each round of passes (a pass per tile).

        Uniform: `size`'s count each round, the last one what is left. With `grow`, the first
        round has `size`'s count and each next one twice the one before, up to the passes the
        lanes allow (as without pass_spp): an early first image, then few launches (each launch
        costs its trace; docs/design/sequence_sampler.md).

        Args:
            width, height: the film's size. spp: the render's camera samples per pixel.

        Returns:
            (the tiles, the rounds' camera samples per pixel, summing to spp).
        """
        layout, first = self.size(width, height, spp)
        cap = first
        if self.grow:
            tw, th = layout[0].size
            cap = max(first, self.lanes_per_pass // (tw * th))
        sizes, done, n = [], 0, first
        while done < spp:
            k = min(n, cap, spp - done)
            sizes.append(k)
            done += k
            n = 2 * n if self.grow else n
        return layout, sizes


@dataclass(frozen=True)
class Unit:
    """One kernel launch of the pass loop (Ray renders each as a task: `ray_plan`).

    Args:
        index: the launch number, round * tiles + tile. tile: its tile's index in the layout.
        round: how many launches of that tile came before it. spp: its camera samples per pixel.
        seed: its seed, `pass_seed(the render's seed, index)`. offset: the camera samples per
        pixel of its tile's launches before it (where it continues the low-discrepancy sequence:
        `unit_sequence`).
    """
    index: int
    tile: int
    round: int
    spp: int
    seed: int
    offset: int = 0


@dataclass(frozen=True)
class Tile:
    """One crop window of the film (all tiles of a render share one size, so the kernel compiles
    once per offset and not per size) and the part of it that is new: edge tiles are shifted inwards
    to stay inside the film, and the pixels they share with their neighbour are dropped."""
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
    """The film as one tile, or as tiles of one size where it has too many pixels.

    Args:
        width, height: the film's crop size in pixels.
        max_pixels: the most pixels of one tile (None: LANES_PER_PASS).

    Returns:
        One Tile where the film has at most `max_pixels` pixels; else tiles of TILE_SIDE columns (or
        the width, if narrower) and as many rows as fit into `max_pixels`, row by row.
    """
    max_pixels = max_pixels or LANES_PER_PASS
    if width * height <= max_pixels:
        return [
            Tile((0, 0), (width, height), (slice(None), slice(None)), (slice(None), slice(None)))
        ]
    tw = min(width, TILE_SIDE, max_pixels)
    th = min(height, max(1, max_pixels // tw))
    return [Tile((x, y), (tw, th), (ky, kx), (dy, dx))
            for y, ky, dy in _axis(height, th) for x, kx, dx in _axis(width, tw)]


class Crop:
    """Crop windows of a sensor's film, set one after another (`set`), and the film's own window
    back when the block ends (a context manager).

    Args:
        sensor: the sensor whose film is cropped.
    """

    def __init__(self, sensor: mi.Sensor):
        film = sensor.film()
        self.sensor, self.params = sensor, None
        self.base = tuple(int(v) for v in film.crop_offset())
        self.full = tuple(int(v) for v in film.crop_size())

    def set(self, offset: tuple[int, int], size: tuple[int, int]) -> None:
        """Set the film's crop window.

        Args:
            offset: (x, y) of the window relative to the film's own crop offset, in pixels.
            size: (width, height) of the window, in pixels.
        """
        if self.params is None:
            self.params = mi.traverse(self.sensor)
        self.params["film.crop_offset"] = mi.ScalarPoint2u(
            self.base[0] + offset[0], self.base[1] + offset[1]
        )
        self.params["film.crop_size"] = mi.ScalarVector2u(*size)
        self.params.update()

    def __enter__(self) -> "Crop":
        return self

    def __exit__(self, *exc) -> bool:
        if self.params is not None:  # leave the scene's film as it was
            self.params["film.crop_offset"] = mi.ScalarPoint2u(*self.base)
            self.params["film.crop_size"] = mi.ScalarVector2u(*self.full)
            self.params.update()
        return False


def memory_needed(width: int, height: int, ext: str = ".exr") -> int:
    """Bytes of host memory a render of this size needs at its peak, while the file is written.

    That is the float32 accumulator, the averaged image, Mitsuba's bitmap of it, and the encoded
    file (up to twice in the growing memory stream, once more as bytes), plus the lanes of one pass.

    Args:
        width, height: the image size in pixels.
        ext: the output's extension (".png": one byte per channel; else four).

    Returns:
        The estimate, in bytes.
    """
    image = width * height * 3 * 4
    encoded = width * height * 3 * (1 if ext == ".png" else 4)
    return 3 * image + 3 * encoded + LANE_BYTES * LANES_PER_PASS


def memory_available() -> int | None:
    """MemAvailable of /proc/meminfo, or less if an address-space limit is set; None where
    unknown.
    """
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
    """Refuse up front an image whose buffers cannot fit into the memory there is.

    Args:
        width, height: the image size in pixels. ext: the output's extension (`memory_needed`).

    Raises:
        UsageError: a side of 2^31 pixels or more, or more than `memory_available()` needed.
    """
    need, have = memory_needed(width, height, ext), memory_available()
    if width >= 1 << 31 or height >= 1 << 31 or (have is not None and need > have):
        have_txt = f"{have / 2**30:.1f} GiB available" if have is not None else "too large"
        raise UsageError(
            f"image {width}x{height} is too large: it needs about {need / 2**30:.1f} GiB of "
            f"memory ({have_txt}); render a smaller --width/--height"
        )


class Progress:
    """State after a pass; `image` is the average of the finished passes, computed when asked for.
    Takes more than 7 parameters: each is one fact of the pass loop's state that the properties
    read, none of them travels with another.

    Args:
        spp_total: the render's camera samples per pixel.
        total: the float32 running sum, H x W x (the image's channels + the error AOVs' sums).
        counts: camera samples per pixel summed so far, per tile. layout: the tiles.
        channels: the image's channels in `total` (None: all of them).
        unit: the launch just done (a recording maps its lanes to the film's pixels with its tile
            and camera samples per pixel: `lookdev.record`), or None.
        in_pixels: the passes kept each sample in its own pixel (`run_passes`' in_pixels).
        groups: the light groups whose Combined follows the image's channels, R G B each
            (`StylizedIntegrator.group_names`); empty: the channels after the image's are the
            error AOVs, if any.
    """

    def __init__(
        self,
        spp_total: int,
        total: np.ndarray,
        counts: np.ndarray,
        layout: list[Tile],
        channels: int | None = None,
        unit: Unit | None = None,
        in_pixels: bool = False,
        groups: tuple = (),
    ):
        self.groups = tuple(groups)
        #: camera samples per pixel every pixel has at least (a tile may have one pass more)
        self.spp_done = int(counts.min())
        self.spp_total = spp_total
        #: each sample counted in its own pixel only (`run_passes`' in_pixels), not the film's
        #: filter
        self.in_pixels = in_pixels
        #: the launch just done (None: none named), and its tile's index in `layout` and its camera
        #: samples per pixel (0, 0 where none is named)
        self.unit = unit
        self.tile, self.pass_spp = (unit.tile, unit.spp) if unit is not None else (0, 0)
        self._total, self._counts, self._tiles = total, counts, layout
        #: the image's channels in `total`; the error AOVs' sums follow them (`AOV_NAMES`)
        self._channels = total.shape[-1] if channels is None else channels

    @property
    def layout(self) -> list[Tile]:
        return self._tiles

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
        `variance`: the variance of each pixel's estimate (its mean over the camera samples), per
        RGB channel: (mean of the squared samples - squared mean) / (spp - 1), the unbiased sample
        variance over spp; NaN where a pixel has fewer than 2 samples. `bias`: the predicted
        direct-application bias of Eq. 21, g''(<I>_n) s^2 / (2n), at the first stylized vertex,
        averaged over the pixel's samples (0 where no child was drawn). `children`: the children
        used there, averaged (n for a fixed count)."""
        if self._channels == self._total.shape[-1] or self.groups:
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


    @property
    def light_groups(self) -> dict[str, np.ndarray] | None:
        """Each light group's Combined (an integrator with light_groups, else None): its styled
        light at the first hit, the environment seen directly in the environment's group; float32
        H x W x 3 by group name, `default` first. Their sum is the image (within float rounding)."""
        if not self.groups:
            return None
        mean, c = self._mean(), self._channels
        return {g: np.ascontiguousarray(mean[..., c + 3 * k:c + 3 * k + 3])
                for k, g in enumerate(self.groups)}


def pass_size(width: int, height: int, spp: int, lanes_per_pass: int = LANES_PER_PASS,
              pass_spp: int | None = None) -> tuple[list[Tile], int]:
    """The tiles and the camera samples per pixel of one pass.

    A function of the image size and the counts only, never of measured time: the same seed gives
    the same image on every run.

    Args:
        width, height: the film's size. spp: the render's camera samples per pixel.
        lanes_per_pass: camera samples per pass. pass_spp: a fixed split (None, 0: from the lanes).

    Returns:
        (the tiles, the camera samples per pixel of one pass, within [1, spp]).
    """
    layout = tiles(width, height)
    tw, th = layout[0].size
    per_pass = pass_spp if pass_spp else max(1, lanes_per_pass // (tw * th))
    return layout, max(1, min(spp, per_pass))


def passes(scene: mi.Scene, integrator: mi.Integrator, spp: int, seed: int = 0,
           lanes_per_pass: int = LANES_PER_PASS, pass_spp: int | None = None
           ) -> Iterator[Progress]:
    """Render `spp` camera samples per pixel in passes, tile by tile; yield the running average
    after each (`run_passes` of this shot and split, the `auto` values pinned here).

    Args:
        scene, integrator: what to render. spp: camera samples per pixel. seed: the render's seed.
        lanes_per_pass, pass_spp: the pass split (`PassSplit`).

    Returns:
        An iterator of `Progress`, one after each pass (with the error AOVs of aovs=True summed).

    Raises:
        UsageError, SceneError: bad arguments, too little memory, aovs on a film other than rgb(a).
    """
    return run_passes(Shot(scene, integrator, spp, seed), PassSplit(lanes_per_pass, pass_spp))


def run_passes(shot: Shot, split: PassSplit = PassSplit(), lock: Any = contextlib.nullcontext(),
               pinned: bool = False, in_pixels: bool = False) -> Iterator[Progress]:
    """The pass loop: `shot` in passes of `split`, tile by tile; the running average after each.

    Args:
        shot: what to render, its camera samples per pixel and seed. split: the pass split.
        lock: held while the sum changes.
        pinned: the `auto` values are pinned already (else `pin_auto_values` pins them here).
        in_pixels: each camera sample counts in its own pixel only, as with a box filter,
            whatever the film's (`kernel.launch.render_pixel_pass`: the image denoiser's input);
            an rgb film and an integrator without error AOVs only.

    Returns:
        An iterator of `Progress`, one after each pass (with the error AOVs of aovs=True summed).

    Raises:
        UsageError, SceneError: bad arguments, too little memory, aovs on a film other than rgb(a).
    """
    scene, integrator, spp, seed = shot.scene, shot.integrator, shot.spp, shot.seed
    check_passes_args(scene, integrator, spp, seed)
    if not pinned:
        integrator = pin_auto_values(scene, integrator)[0]
    sensor = scene.sensors()[0]
    film = sensor.film()
    width, height = (int(v) for v in film.crop_size())
    check_memory(width, height)
    layout, rounds = split.rounds(width, height, spp)
    # the film's own: RGB, Y, XYZ, with alpha or not
    channels = len(PIXEL_FORMATS[film_format(scene)])
    # error AOVs (StylizedIntegrator.aov_names), after the film's channels
    extra = len(integrator.aov_names())
    if extra and film_format(scene) not in ("rgb", "rgba"):
        raise UsageError(
            f"aovs need an rgb or rgba film (the variance is per RGB channel); the scene's film is "
            f"{film_format(scene)!r}"
        )
    total = np.zeros((height, width, channels + extra), dtype=np.float32)
    groups = tuple(getattr(integrator, "group_names", list)())
    counts = np.zeros(len(layout), dtype=np.int64)
    index = 0
    # the expansion pass (expansion_pass > 0): once per tile and render, before the tile's
    # first pass
    expand = getattr(integrator, "prepare_expansion", None)
    if expand is not None:
        integrator.expansion.clear()
    with Crop(sensor) as crop:
        while counts[-1] < spp:
            for t, tile in enumerate(layout):
                n = rounds[index // len(layout)]
                unit = Unit(index, t, index // len(layout), n, pass_seed(seed, index),
                            int(counts[t]))
                if len(layout) > 1:
                    crop.set(tile.offset, tile.size)
                if expand is not None:
                    expand(scene, expansion_seed(seed, t))
                # recorded and launched with no scene finalised meanwhile (jit.no_collection)
                with no_collection():
                    launch = render_pixel_pass if in_pixels else render_pass
                    img = launch(scene, integrator, n, unit.seed, unit_sequence(seed, unit))
                    arr = np.asarray(img, dtype=np.float32)[..., :channels + extra]
                with lock:
                    total[tile.dest] += arr[tile.keep] * np.float32(n)
                    counts[t] += n
                del img, arr
                index += 1
                yield Progress(spp, total, counts, layout, channels, unit, in_pixels, groups)


def pass_count(
    scene: mi.Scene, spp: int, lanes_per_pass: int = LANES_PER_PASS, pass_spp: int | None = None,
    grow: bool = False
) -> int:
    """How many kernel launches `passes` makes: tiles times passes per tile.

    Args:
        scene: the scene (its film's crop size). spp: camera samples per pixel.
        lanes_per_pass, pass_spp, grow: the pass split (`PassSplit`).

    Returns:
        The number of launches.
    """
    size = scene.sensors()[0].film().crop_size()
    layout, rounds = PassSplit(lanes_per_pass, pass_spp, grow).rounds(int(size[0]), int(size[1]),
                                                                      spp)
    return len(layout) * len(rounds)


__all__ = [
    "LANES_PER_PASS",
    "TILE_SIDE",
    "LANE_BYTES",
    "pass_seed",
    "unit_sequence",
    "expansion_seed",
    "Shot",
    "PassSplit",
    "Unit",
    "Tile",
    "tiles",
    "Crop",
    "pin_auto_values",
    "memory_needed",
    "memory_available",
    "check_memory",
    "Progress",
    "pass_size",
    "passes",
    "run_passes",
    "pass_count",
]
