"""The film's reconstruction filter for buffers: where Mitsuba put each sample, and its splat.

    spec = describe_filter(film.rfilter())  # the header's filter: {"type": "gaussian", ...}
    pos = positions(sensor, spp, seed)     # 2 x N float32: each camera sample's film position
    img = develop(buf, values)             # the restyled image, as Mitsuba's film develops it

`positions` draws the sensor sampler's first `next_2d()` from a clone of it, bit for bit the
render's; `develop` splats with `rfilter.eval` per pass into an ImageBlock, develops, keeps the
tile's pixels and averages the passes by spp. How Mitsuba places and weighs samples:
docs/design/expectation_buffer.md.
"""
from __future__ import annotations

import re
from fractions import Fraction
from functools import lru_cache
from typing import Any

import numpy as np

from styletrace.errors import SceneError
from styletrace.gate import dr, mi
from styletrace.host_arrays import aligned
from styletrace.kernel.launch import in_sequence, seeded_positions

BOX = {"type": "box"}
#: Mitsuba class -> (plugin name, parameters read from its radius or description)
_KINDS = {"BoxFilter": "box", "TentFilter": "tent", "GaussianFilter": "gaussian",
          "MitchellNetravaliFilter": "mitchell", "CatmullRomFilter": "catmullrom",
          "LanczosSincFilter": "lanczos"}


def is_box(spec: Any) -> bool:
    """Whether a header's filter entry is a box.

    Args:
        spec: the entry: "box", a spec dict, or None (a buffer older than filters: a box).

    Returns:
        True for a box.
    """
    return spec in (None, "box") or (isinstance(spec, dict) and spec.get("type") == "box")


def _candidates(rfilter) -> list[dict]:
    kind = _KINDS.get(rfilter.class_name())
    if kind is None:
        return []
    r = float(rfilter.radius())
    if kind in ("box", "catmullrom"):
        return [{"type": kind}]
    if kind == "tent":
        return [{"type": kind, "radius": r}]
    if kind == "gaussian":
        return [{"type": kind, "stddev": r / 4.0}]  # Mitsuba: radius = 4 stddev (exact in binary)
    if kind == "lanczos":
        return [{"type": kind, "lobes": int(round(r))}]
    # mitchell: B and C, printed to 6 digits
    text = dict(re.findall(r"(\w+)=([-+0-9.eE]+)", str(rfilter)))
    b, c = float(text.get("B", 1 / 3)), float(text.get("C", 1 / 3))
    near = [(float(Fraction(v).limit_denominator(12)), v) for v in (b, c)]
    return [{"type": kind, "B": x, "C": y} for x in near[0] for y in near[1]]


def describe_filter(rfilter) -> dict:
    """The film's filter as a plugin dict that `build_filter` turns back into the same filter.

    Args:
        rfilter: the film's mi.ReconstructionFilter.

    Returns:
        The spec ({"type": "gaussian", "stddev": 0.5}, ...) whose filter has the same radius and an
        `eval` equal at every tested offset.

    Raises:
        SceneError: a filter that cannot be rebuilt so (one line).
    """
    xs = mi.Float(aligned(np.linspace(-4.0, 4.0, 257)))
    want = np.asarray(rfilter.eval(xs))
    for spec in _candidates(rfilter):
        try:
            got = np.asarray(build_filter(_key(spec)).eval(xs))
        except Exception:  # noqa: BLE001 - a parameter Mitsuba refuses: try the next candidate
            continue
        same_radius = float(build_filter(_key(spec)).radius()) == float(rfilter.radius())
        if np.array_equal(got, want) and same_radius:
            return spec
    raise SceneError(f"the film's reconstruction filter '{rfilter.class_name()}' cannot be "
                     f"recorded in a buffer: use box, tent, gaussian, mitchell, catmullrom or "
                     f"lanczos")


def _key(spec: dict) -> tuple:
    return tuple(sorted(spec.items()))


@lru_cache(maxsize=16)
def build_filter(key: tuple):
    """The Mitsuba filter of a spec, made once per spec and cached (16 kept).

    Args:
        key: the spec's items as a sorted tuple (`_key`).

    Returns:
        The mi.ReconstructionFilter `mi.load_dict` makes of it.
    """
    return mi.load_dict(dict(key))


def rebuild(spec: Any):
    """The filter of a header's entry.

    Args:
        spec: the header's "filter" entry (`is_box` entries: a box).

    Returns:
        The mi.ReconstructionFilter (`build_filter`).
    """
    return build_filter(_key(BOX if is_box(spec) else dict(spec)))


def pixel_kernel(rfilter, steps: int = 64) -> np.ndarray:
    """The filter's weights on a smooth image of pixel means: for a pixel offset k, the integral
    of f(x) times the linear interpolation's hat around k (what the film makes of a smooth image
    known at pixel centres), normalised to sum 1.

    Args:
        rfilter: the film's mi.ReconstructionFilter (separable: f(x, y) = f(x) f(y)).
        steps: integration points per pixel.

    Returns:
        1-D float64 weights for offsets -r .. r (r = ceil(radius)); [1.0] for a box.
    """
    if rfilter.is_box_filter():
        return np.ones(1)
    r = int(np.ceil(float(rfilter.radius())))
    x = (np.arange(-(r + 1) * steps, (r + 1) * steps + 1) + 0.0) / steps
    f = np.asarray(rfilter.eval(mi.Float(x)), dtype=np.float64)
    weights = np.array([np.sum(f * np.maximum(1.0 - np.abs(x - k), 0.0)) for k in range(-r, r + 1)])
    return weights / weights.sum()


def filtered_pixels(image: np.ndarray, rfilter) -> np.ndarray:
    """A smooth image of pixel means (a denoised one) as the film's filter would develop it
    (`pixel_kernel` along each axis, edges repeated).

    Args:
        image: H x W x C float array. rfilter: the film's mi.ReconstructionFilter.

    Returns:
        H x W x C float32; `image` itself for a box.
    """
    k = pixel_kernel(rfilter)
    if len(k) == 1:
        return image
    r = len(k) // 2
    out = np.asarray(image, dtype=np.float64)
    for axis in (0, 1):
        pad = [(0, 0)] * out.ndim
        pad[axis] = (r, r)
        padded = np.pad(out, pad, mode="edge")
        n = out.shape[axis]
        out = sum(w * np.take(padded, range(i, i + n), axis=axis) for i, w in enumerate(k))
    return out.astype(np.float32)


def positions(sensor, spp: int, seed: int, device: bool = False, sequence=None):
    """Each camera sample's film position in a pass, bit for bit the render's.

    Args:
        sensor: the mi.Sensor, its film as it is set now (crop window, border sampling).
        spp, seed: the pass's camera samples per pixel and seed.
        device: return the Dr.Jit array (a recording keeps it there: `buffer.Arrays`).
        sequence: the pass's place in its render's sequence (`passes.unit_sequence`), as the
            render launched it (`owen_sobol` samplers).

    Returns:
        2 x lanes float32 positions in pixels of the full film (crop offset included): numpy, or
        with `device` a mi.Point2f, evaluated.
    """
    film = sensor.film()
    b = int(film.rfilter().border_size()) if film.sample_border() else 0
    with in_sequence(sensor, sequence):
        _, pos = seeded_positions(sensor, spp, seed, b, [int(v) for v in film.crop_offset()])
    pos = mi.Point2f(pos)
    dr.eval(pos)
    if device:
        return pos
    return np.stack([np.asarray(pos.x, dtype=np.float32), np.asarray(pos.y, dtype=np.float32)])


def _keep_index(tile: dict, width: int) -> tuple[np.ndarray, np.ndarray]:
    """(pixels of the tile's block, pixels of the film) that a tile keeps, row-major indices."""
    (tw, _), (ox, oy) = tile["size"], tile["offset"]
    r0, r1, c0, c1 = tile["keep"]
    ys, xs = np.mgrid[r0:r1, c0:c1]
    return ((ys * tw + xs).ravel().astype(np.uint32),
            ((ys + oy) * width + xs + ox).ravel().astype(np.uint32))


def develop(buffer, values) -> mi.Float:
    """The image of per-sample values as Mitsuba's film develops it, pass by pass.

    Args:
        buffer: a Buffer recorded with a filter other than a box, its Dr.Jit arrays made
            (`restyle.device`: `pos`); the tiles' pixel indices are cached there.
        values: mi.Color3f, one lane per camera sample.

    Returns:
        mi.Float, flat H*W*3 row-major RGB: the passes averaged by spp; differentiable in values.
    """
    d = buffer.device
    rf = rebuild(buffer.header["filter"])
    w, h = buffer.width, buffer.height
    base = buffer.header.get("crop_offset", [0, 0])
    layout = buffer.header["layout"]
    if "keep_index" not in d:
        d["keep_index"] = [tuple(mi.UInt32(aligned(a, np.uint32)) for a in _keep_index(t, w))
                           for t in layout]
    llvm = mi.variant().startswith("llvm")
    total = dr.zeros(mi.Float, w * h * 3)
    spp = np.zeros(w * h, dtype=np.float32)
    start = 0
    for p in buffer.header["passes"]:
        count, n, t = int(p["samples"]), int(p["spp"]), int(p.get("tile", 0))
        tile = layout[t]
        idx = dr.arange(mi.UInt32, start, start + count)
        start += count
        corner = mi.ScalarPoint2i(base[0] + tile["offset"][0], base[1] + tile["offset"][1])
        block = mi.ImageBlock(mi.ScalarVector2u(*tile["size"]), corner, 4, rf, False, False,
                              llvm and n >= 4)
        block.put(dr.gather(mi.Point2f, d["pos"], idx),
                  [dr.gather(mi.Float, values[c], idx) for c in range(3)] + [mi.Float(1.0)])
        data = block.tensor().array
        src, dst = d["keep_index"][t]
        weight = dr.gather(mi.Float, data, src * 4 + 3)
        weight = dr.select(weight == 0.0, 1.0, weight)
        for c in range(3):
            value = dr.gather(mi.Float, data, src * 4 + c) / weight * n
            dr.scatter_reduce(dr.ReduceOp.Add, total, value, dst * 3 + c)
        spp[_keep_index(tile, w)[1]] += n
    return total / mi.Float(aligned(np.repeat(np.maximum(spp, 1.0), 3)))


__all__ = ["describe_filter", "build_filter", "rebuild", "is_box", "positions", "develop", "BOX",
           "pixel_kernel", "filtered_pixels"]
