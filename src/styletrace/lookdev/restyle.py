"""Restyling an expectation buffer: g_θ evaluated again over the stored camera samples.

    img = styletrace.restyle(buf, style="cel", thresholds=(0.2, 0.6))   # H x W x 3, linear

Per camera sample L_before + beta g_θ(mean, vertex), accumulated as the film does (`accumulate`;
`lookdev.film_filter` for other filters); equal to a fresh render with the same seed and n up to
float rounding. Sequence buffers are replayed (`lookdev.sequence.replay`). Refused with one line:
estimators other than direct and affine on a mean buffer, another n, a per-sample style (acp),
children needed from a closed-form recording, a replay beyond what is stored. See
docs/design/expectation_buffer.md.
"""
from __future__ import annotations

import copy
import json
import os
from dataclasses import replace
from functools import lru_cache
from types import SimpleNamespace
from typing import Any

import numpy as np

from styletrace.config import settings as S
from styletrace.config.estimator_registry import MEAN_ESTIMATORS, applicable
from styletrace.errors import StyletraceError, UsageError
from styletrace.estimators import apply_linear
from styletrace.estimators.arrays import const_like
from styletrace.gate import dr, mi
from styletrace.host_arrays import aligned
from styletrace.lookdev import film_filter
from styletrace.lookdev.buffer import (
    DENOISED,
    PILOT,
    SPREAD,
    Arrays,
    Buffer,
    fields_for,
    load_buffer,
)
from styletrace.lookdev.sequence import device_arrays, replay
from styletrace.scene.defaults import Facts, auto_values
from styletrace.styles import style_class
from styletrace.styles.base import Vertex
from styletrace.styles.gradient import Gradient

# ---- the value of one camera sample --------------------------------------------------------------

def finish_slot(slot: S.StyleSlot, mean: mi.Color3f, v: Vertex) -> mi.Color3f:
    """A slot's estimate from the mean of its n children, as its estimator computes it in the
    kernel (`direct`: g(mean); `affine`: a1 mean + a0; closed-form styles: g of nothing).

    Args:
        slot: the StyleSlot (style, n, estimator: direct or affine).
        mean: mi.Color3f, the children's mean per lane; v: the lanes' Vertex.

    Returns:
        mi.Color3f, the estimate per lane.
    """
    style = slot.style
    if style.closed_form:
        return style.apply(mi.Color3f(0.0), v)
    if slot.estimator == "affine":  # estimators.Affine.value: a1 <I> + a0
        form = style.form()
        a0 = np.asarray(form.a0, dtype=np.float64)
        return apply_linear(np.asarray(form.a1, dtype=np.float64), mean) + const_like(a0, mean)
    return style.apply(mean, v)


#: (z, weight): 5-point Gauss-Hermite quadrature for z ~ N(0, 1)
#: (numpy.polynomial.hermite_e.hermegauss(5), weights over sqrt(2 pi)); exact for polynomials in z
#: up to degree 9
SPREAD_NODES = ((0.0, 0.53333333), (1.35562618, 0.22207592), (-1.35562618, 0.22207592),
                (2.85697001, 0.01125741), (-2.85697001, 0.01125741))


def finish_spread(slot: S.StyleSlot, mean: mi.Color3f, v: Vertex, spread) -> mi.Color3f:
    """A slot's estimate averaged over a relative uncertainty of the mean (a denoised D's).

    Args:
        slot, mean, v: as for `finish_slot`.
        spread: mi.Float, the mean's relative standard error per lane (0: `finish_slot`).

    Returns:
        mi.Color3f: E over z ~ N(0, 1) of finish_slot(slot, mean (1 + spread z), v), by
        quadrature (SPREAD_NODES), the scaled mean clamped at 0.

    Design: docs/denoise.md, step 7 (why the mean of g over D's error).
    """
    out = mi.Color3f(0.0)
    for z, weight in SPREAD_NODES:
        out += weight * finish_slot(slot, dr.maximum(mean * (1.0 + spread * z), 0.0), v)
    return out


# ---- slots: what the header records, and what a restyle makes of it ------------------------------

def _jsonable(value: Any) -> Any:
    if isinstance(value, Gradient):
        return value.spec
    if isinstance(value, tuple):
        return [_jsonable(v) for v in value]
    return value


def slot_record(slot: S.StyleSlot, owner: str, ident: str = "") -> dict:
    """A style slot as the buffer's header keeps it (exact parameter values, JSON).

    Args:
        slot: the StyleSlot.
        owner: "integrator" or "object" (a `styled` BSDF's slot); ident: that BSDF's id.

    Returns:
        {"owner", "id", "style", "params", "inner" (0 for closed-form styles), "estimator"}.
    """
    style = slot.style
    return {"owner": owner, "id": ident, "style": style.name,
            "params": {p.name: _jsonable(style.values[p.name]) for p in style.params},
            "inner": 0 if style.closed_form else slot.n(0), "estimator": slot.estimator}


def changed_owner(buffer: Buffer) -> str:
    """Which slots a restyle changes.

    Args:
        buffer: the buffer.

    Returns:
        "object" (every styled object's) for first_object_hit, else "integrator".
    """
    return "object" if buffer.stylize == "first_object_hit" else "integrator"


def slots_for(
    buffer: Buffer,
    style: str | None = None,
    estimator: str | None = None,
    inner: Any = None,
    **params: Any,
) -> list[S.StyleSlot]:
    """The style slots of a restyle: the recorded ones, those of `changed_owner` changed.

    Args:
        buffer: the Buffer; style: the new style (None: the recorded; a new one starts at defaults).
        estimator, inner: None keeps the recorded ones (or direct); a new n needs a sequence buffer.
        params: new values (None ignored); with them, the pilot's auto choices are made again.

    Returns:
        One StyleSlot per header slot.

    Raises:
        UsageError: a change the buffer cannot replay; StyleError, SettingsError: bad values.
    """
    slots = []
    for rec in buffer.header["slots"]:
        values = {"style": rec["style"], **rec["params"]}
        est = rec["estimator"]
        n = int(rec["inner"])
        if rec["owner"] == changed_owner(buffer):
            given = {k: v for k, v in params.items() if v is not None}
            # new values: the pilot's choices are made again
            if given and style in (None, rec["style"]):
                values = {k: v for k, v in values.items() if k not in rec.get("auto", ())}
            values = S.refine_values(values, {k: v for k, v in {"style": style, **params}.items()
                                              if v is not None})
            new = style_class(str(values["style"]))()
            if inner is not None and S.adaptive(S.parse_inner(inner, 1)):
                raise UsageError(
                    f"bad value {inner!r} for inner: a buffer replays a fixed count of children; "
                    f"adaptive counts n0:n_max need a new render"
                )
            if inner is not None and buffer.stores == "sequence":
                # the replay finds out whether the stored sequence suffices
                n = S.parse_inner(inner, 1)[0]
            elif inner is not None and S.parse_inner(inner, 1) != (n,):
                raise UsageError(
                    f"bad value {inner!r} for inner: the buffer holds the mean of n = {n} children "
                    f"per camera sample; another n needs a new render"
                )
            if new.per_sample:
                raise UsageError(
                    f"style '{new.name}' cannot restyle: it applies g to every child sample, and a "
                    f"buffer keeps only their mean"
                )
            if n == 0 and not new.closed_form:
                raise UsageError(
                    f"style '{new.name}' cannot restyle this buffer: it was recorded with the "
                    f"closed-form style '{rec['style']}' (0 children) and '{new.name}' needs n >= "
                    "1; record the buffer with a style that traces children"
                )
            if estimator is not None:
                est = estimator
            elif est not in applicable(new):
                est = "direct"
        if est not in MEAN_ESTIMATORS and buffer.stores == "mean":
            raise UsageError(
                f"estimator '{est}' cannot restyle: it needs the children themselves, and a buffer "
                f"keeps only their mean; use {' or '.join(MEAN_ESTIMATORS)}"
            )
        slots.append(S.parse_slot({**values, "inner_samples": max(n, 1), "estimator": est},
                                  context="restyle"))
    return slots


# ---- the kernel ----------------------------------------------------------------------------------

#: the Dr.Jit type of each per-sample array a restyle reads (`field`)
FIELD_TYPES = {"p": "Point3f", "n": "Vector3f", "wo": "Vector3f", "mean": "Color3f",
               "L_before": "Color3f", "beta": "Color3f", DENOISED: "Color3f", "pos": "Point2f",
               "slot": "Int32", "pixel": "UInt32", "depth": "UInt32", SPREAD: "Float"}


#: the numpy dtype each scalar Dr.Jit type of FIELD_TYPES is made from
_SCALAR = {"Int32": np.int32, "UInt32": np.uint32, "Float": np.float32}


def _on_device(part, kind: str):
    """One part of a buffer's array as the Dr.Jit type `kind` (a numpy part is wrapped)."""
    T = getattr(mi, kind)
    if not isinstance(part, np.ndarray):
        return T(part)
    # aligned: one kernel code whatever numpy's allocation (host_arrays)
    if kind in _SCALAR:
        return T(aligned(part, _SCALAR[kind]))
    return T(*(mi.Float(aligned(part[i])) for i in range(part.shape[0])))


def field(buffer: Buffer | Arrays, name: str):
    """One per-sample array of the buffer as a Dr.Jit array, its pass parts joined on the device.

    Args:
        buffer: the Buffer, or its `Arrays`. name: the array (FIELD_TYPES names its type).

    Returns:
        The Dr.Jit array (a Dr.Jit part is used as it is, a numpy part wrapped); not cached:
        `device` keeps what a restyle reads.

    Raises:
        KeyError: the buffer has no such array.
    """
    arrays = buffer if isinstance(buffer, Arrays) else buffer.arrays
    return joined(arrays.parts(name), FIELD_TYPES[name])


def joined(parts: list, kind: str):
    """A per-sample array's pass parts as one Dr.Jit array of type `kind`, joined on the device.

    Args:
        parts: the parts, numpy (wrapped) or Dr.Jit (used as they are). kind: the Dr.Jit type's
            name in `mi` (FIELD_TYPES' values).

    Returns:
        The Dr.Jit array (`join`: evaluated where there were several parts).
    """
    parts = [_on_device(p, kind) for p in parts]
    if len(parts) == 1:
        return parts[0]
    if kind in _SCALAR:
        return getattr(mi, kind)(join(parts))
    return getattr(mi, kind)(*(join([p[i] for p in parts]) for i in range(len(parts[0]))))


#: the most parts one `dr.concat` joins: its cost grows faster than their count (measured, 4096
#: floats a part: 16 parts 0.01 s, 357 parts 1.1 s evaluated alone and 10 s fused into the kernel
#: that read them, a Ctrl-C's finish after 357 passes of 32 x 32)
JOIN = 16


def join(parts: list):
    """Dr.Jit arrays of one type joined end to end, JOIN at a time, each join evaluated.

    Args:
        parts: the arrays (at least one).

    Returns:
        The joined array, evaluated (a single part as it is).
    """
    while len(parts) > 1:
        groups = [parts[i:i + JOIN] for i in range(0, len(parts), JOIN)]
        parts = [g[0] if len(g) == 1 else dr.concat(g) for g in groups]
        dr.eval(*parts)
    return parts[0]


def device(buffer: Buffer) -> dict[str, Any]:
    """The buffer's arrays as Dr.Jit arrays, made once per buffer and kept in `buffer.device`.

    Args:
        buffer: the Buffer.

    Returns:
        The arrays by name (p, n, wo, mean, L_before, slot, pixel, depth, ...), with the
        summation order and weights `accumulate` uses. Arrays the recording kernel left on the
        device are used as they are (`buffer.Arrays`): nothing is copied to the host but `pixel`.
    """
    d = buffer.device
    if "slot" in d:
        return d
    a = buffer.arrays
    for k in ("p", "n", "wo", "L_before"):
        d[k] = field(buffer, k)
    if buffer.stores == "mean":
        d["mean"] = field(buffer, "mean")
    else:
        d.update(device_arrays(a))
    # a denoised render (docs/denoise.md): each sample styles the denoised E[L]
    if DENOISED in a:
        d["mean"] = field(buffer, DENOISED)
    if SPREAD in a:  # and averages the style over D's uncertainty (`finish_spread`)
        d["spread"] = field(buffer, SPREAD)
    d["slot"] = field(buffer, "slot")
    pixel = a["pixel"]
    d["pixel"] = mi.UInt32(aligned(pixel, np.uint32))
    if "beta" in a:
        d["beta"], d["depth"] = field(buffer, "beta"), field(buffer, "depth")
    else:
        d["depth"] = dr.zeros(mi.UInt32, buffer.camera_samples)
    if buffer.filtered:  # splatted with the film's filter (`film_filter.develop`)
        d["pos"] = field(buffer, "pos")
        dr.eval(*[x for x in d.values()])
        return d
    counts = np.bincount(pixel, minlength=buffer.width * buffer.height)
    if counts.size and counts.min() == counts.max() > 0:
        # every pixel holds k samples: `accumulate` sums them in a fixed order (see there); in
        # pixel order already (coverage points, one pass): that order is the samples' own
        in_order = pixel.size < 2 or bool(np.all(pixel[1:] >= pixel[:-1]))
        d["by_pixel"] = (None if in_order else
                         mi.UInt32(np.argsort(pixel, kind="stable").astype(np.uint32)))
        d["per_pixel"] = int(counts[0])
    counts = counts.astype(np.float32)
    d["inv_weight"] = mi.Float(aligned(np.repeat(1.0 / np.maximum(counts, 1.0), 3)))
    dr.eval(*[x for x in d.values() if x is not None and not isinstance(x, int)])
    return d


def camera_scene(buffer: Buffer) -> mi.Scene:
    """A scene holding only the recorded camera, for styles that read it in `prepare` (hatching
    and halftone project their spacing through it, gooch and xtoon take its frame).

    Args:
        buffer: the Buffer (its header's sensor_to_world and sensor).

    Returns:
        An mi.Scene: the camera's kind, field of view and film; a buffer older than the sensor
        entry gets a default perspective camera with the recorded frame.
    """
    m = mi.ScalarTransform4f(np.asarray(buffer.header["sensor_to_world"], dtype=np.float64))
    sensor = buffer.header.get("sensor")
    if sensor is None:  # a buffer written before the sensor was kept: its frame alone
        return mi.load_dict({"type": "scene", "camera": {"type": "perspective", "to_world": m}})
    w, h = sensor["size"]
    (cw, ch), (cx, cy) = sensor["crop_size"], sensor["crop_offset"]
    film = {"type": "hdrfilm", "width": w, "height": h, "crop_offset_x": cx, "crop_offset_y": cy,
            "crop_width": cw, "crop_height": ch}
    camera = {"type": sensor["kind"], "to_world": m, "film": film}
    if sensor["kind"] == "perspective":
        camera.update(fov=sensor["x_fov"], fov_axis="x")
    return mi.load_dict({"type": "scene", "camera": camera})


@lru_cache(maxsize=4)
def _camera_scene(camera: str) -> mi.Scene:
    """`camera_scene` of the buffers with this camera (JSON of the header's sensor_to_world and
    sensor), kept: making it took 2 ms of a 4 ms restyle of 512 x 512 samples (a slider's)."""
    header = dict(zip(("sensor_to_world", "sensor"), json.loads(camera)))
    if header["sensor"] is None:
        del header["sensor"]
    return camera_scene(Buffer(header, {}))


def resolve_auto(buffer: Buffer, slots: list[S.StyleSlot], scene: mi.Scene) -> list[S.StyleSlot]:
    """Pin the styles' 'auto' values from the pilot the buffer kept, as a render of the scene pins
    them (`scene.defaults`).

    Args:
        buffer: the Buffer (its pilot arrays and each slot's pilot_owner).
        slots: the restyle's StyleSlots, one per header slot; scene: the camera scene.

    Returns:
        The slots, styles pinned; unchanged for a buffer without a pilot.
    """
    # by key: `items()` would copy every array of the buffer to the host, the pilot's alone needed
    pilot = {k[len(PILOT):]: buffer.arrays[k] for k in list(buffer.arrays) if k.startswith(PILOT)}
    if not pilot:
        return slots
    stored = SimpleNamespace(records=pilot)
    out = []
    for rec, slot in zip(buffer.header["slots"], slots):
        chosen = auto_values(slot.style, Facts(scene, stored, int(rec.get("pilot_owner", 0))))
        out.append(replace(slot, style=slot.style.pinned(chosen)) if chosen else slot)
    return out


def prepare_slots(buffer: Buffer, slots: list[S.StyleSlot]) -> list[S.StyleSlot]:
    """The slots ready to evaluate: auto values resolved, each style prepared on the recorded
    camera (`camera_scene`).

    Args:
        buffer: the Buffer; slots: its restyle's StyleSlots (`slots_for`).

    Returns:
        The slots (their styles prepared in place) on the camera's scene (made once per camera:
        `_camera_scene`).
    """
    scene = _camera_scene(json.dumps([buffer.header["sensor_to_world"],
                                      buffer.header.get("sensor")]))
    slots = resolve_auto(buffer, slots, scene)
    for slot in slots:
        slot.style.prepare(scene)
    return slots


def sample_values(buffer: Buffer, slots: list[S.StyleSlot]) -> mi.Color3f:
    """Each camera sample's contribution with the given slots.

    Args:
        buffer: the Buffer; slots: prepared StyleSlots, one per header slot (`prepare_slots`).

    Returns:
        mi.Color3f, one lane per camera sample: L_before + beta g (L_before where no stylized
        vertex); differentiable in the styles' θ for "mean" buffers.

    Raises:
        UsageError: a sequence buffer whose replay needs more than is stored (`replayed`).
    """
    d = device(buffer)
    v = Vertex(p=d["p"], n=d["n"], wo=d["wo"], view=mi.Vector3f(*buffer.header["view"]),
               depth=d["depth"])
    if buffer.stores == "sequence":
        total = replayed(buffer, d, slots, v)
    else:
        total = mi.Color3f(0.0)
        for i, slot in enumerate(slots):
            value = (finish_slot(slot, d["mean"], v) if "spread" not in d
                     else finish_spread(slot, d["mean"], v, d["spread"]))
            total = dr.select(d["slot"] == i, value, total)
    found = d["slot"] >= 0
    if "beta" in d:
        return d["L_before"] + dr.select(found, d["beta"] * total, 0.0)
    return dr.select(found, total, d["L_before"])


def replayed(buffer: Buffer, d: dict, slots: list[S.StyleSlot], v: Vertex) -> mi.Color3f:
    """The slots' estimators replayed over a sequence buffer's stored sequences.

    Args:
        buffer: the sequence Buffer; d: its Dr.Jit arrays (`device`).
        slots: prepared StyleSlots; v: the camera samples' Vertex.

    Returns:
        mi.Color3f, each slot's estimate per camera sample.

    Raises:
        UsageError: a camera sample whose estimator needs more than is stored, or another order.
    """
    total, bad = replay(d, d["slot"], slots, v)
    bad = bad & (d["slot"] >= 0)
    dr.eval(total, bad)
    missing = int(dr.count(bad)[0]) if dr.width(bad) else 0
    if missing:
        a = buffer.arrays
        children, events = int(a["seq_kind"].sum()), int(a["seq_count"].sum())
        names = sorted({s.estimator for s in slots})
        recorded = sorted({r["estimator"] for r in buffer.header["slots"]})
        raise UsageError(
            f"estimator {', '.join(repr(n) for n in names)} cannot restyle this buffer: on "
            f"{missing} of {buffer.camera_samples} camera samples it asks for a child or uniform "
            "number beyond the stored ones or in another order than the recorded "
            f"{', '.join(repr(n) for n in recorded)} (the buffer stores "
            f"{children / buffer.camera_samples:.1f} children and "
            f"{(events - children) / buffer.camera_samples:.1f} uniform numbers per camera sample "
            "on average); this estimator needs more: record a buffer with it"
        )
    return total


def replay_lanes(
    buffer: Any,
    style: str | None = None,
    estimator: str | None = None,
    inner: Any = None,
    **params: Any,
) -> tuple[np.ndarray, np.ndarray]:
    """A sequence buffer's per-sample contributions with a new style, without the refusal of
    lanes that need more than is stored (for inspection and tests).

    Args:
        buffer, style, estimator, inner, params: as for `restyle`.

    Returns:
        (N x 3 float32 contributions, N bool: the samples whose replay needs more than is stored).

    Raises:
        UsageError: a buffer that is not a sequence buffer, or a change `slots_for` refuses.
    """
    buf = as_buffer(buffer)
    if buf.stores != "sequence":
        raise UsageError("replay_lanes needs a sequence buffer (recorded with an unbiased "
                         "estimator)")
    slots = prepare_slots(buf, slots_for(buf, style, estimator, inner, **params))
    d = device(buf)
    v = Vertex(p=d["p"], n=d["n"], wo=d["wo"], view=mi.Vector3f(*buf.header["view"]),
               depth=d["depth"])
    total, bad = replay(d, d["slot"], slots, v)
    found = d["slot"] >= 0
    value = (d["L_before"] + dr.select(found, d["beta"] * total, 0.0) if "beta" in d
             else dr.select(found, total, d["L_before"]))
    return (np.stack([np.asarray(value[i], dtype=np.float32) for i in range(3)], axis=1),
            np.asarray(bad & found, dtype=bool))


def accumulate(buffer: Buffer, values: mi.Color3f) -> mi.Float:
    """The image of per-sample values as the film makes it.

    Box filter: the per-pixel mean of the samples, summed in one order on every run where every
    pixel holds the same number of samples (else by atomic adds: the last bit may vary). Other
    filters: `film_filter.develop` (atomic adds). Design: docs/design/expectation_buffer.md.

    Args:
        buffer: the Buffer; values: mi.Color3f, one lane per camera sample.

    Returns:
        mi.Float, flat H*W*3 row-major RGB; differentiable in the values.
    """
    d = device(buffer)
    if buffer.filtered:
        return film_filter.develop(buffer, values)
    if "per_pixel" in d:
        k, order = d["per_pixel"], d["by_pixel"]
        out = [dr.block_sum(values[c] if order is None else dr.gather(mi.Float, values[c], order),
                            k) for c in range(3)]
        rgb = dr.zeros(mi.Float, buffer.width * buffer.height * 3)
        idx = dr.arange(mi.UInt32, buffer.width * buffer.height) * 3
        for c in range(3):
            dr.scatter(rgb, out[c], idx + c)
        return rgb * d["inv_weight"]
    out = dr.zeros(mi.Float, buffer.width * buffer.height * 3)
    base = d["pixel"] * 3
    for c in range(3):
        dr.scatter_reduce(dr.ReduceOp.Add, out, values[c], base + c)
    return out * d["inv_weight"]


def as_buffer(buffer: Any) -> Buffer:
    """A Buffer, loaded where a path is given.

    Args:
        buffer: a Buffer, or the path (str or path-like) of its .npz file.

    Returns:
        The Buffer.

    Raises:
        UsageError: another type, or a file `load_buffer` refuses.
    """
    if isinstance(buffer, Buffer):
        return buffer
    if isinstance(buffer, (str, os.PathLike)):
        return load_buffer(buffer)
    raise UsageError(f"bad buffer {type(buffer).__name__}: expected a styletrace Buffer or a .npz "
                     "path")


def per_pixel(buffer: Any, point: int = 0) -> Buffer:
    """One sample per pixel of a buffer, to restyle in milliseconds while a slider moves.

    Of every pixel the view keeps its `point`-th sample in the buffer's order (0: the first: of
    the denoiser's coverage points, one cell of the pixel's jittered grid; of camera samples, the
    first pass's first), gathered where the buffer's arrays lie (Dr.Jit arrays on the device), D
    and its spread with it where the buffer is denoised. A restyle of the view is each pixel's one
    value L_before + beta g(mean, vertex), exactly the value that sample has in a restyle of the
    whole buffer (`sample_values`): the image of the whole buffer restricted to those samples, a
    box of one sample per pixel whatever the film's filter. The view is made once per buffer and
    point and kept (in `buffer.device`, dropped when the buffer grows or its D changes).

    Args:
        buffer: a "mean" Buffer (denoised or not) or the path of its .npz file.
        point: which of each pixel's samples, >= 0; a pixel with no more samples than that is
            left out (0, black, in the view's restyle). A filtered buffer's samples that lie in a
            neighbour's pixel or the border (`own` 0) are not counted.

    Returns:
        The view: a Buffer of at most one sample per pixel, in pixel order, box filter, one pass
        of spp 1 (`header["per_pixel"]`: the point and the buffer's sample count), the pilot and
        camera of the buffer.

    Raises:
        UsageError: a sequence buffer (a replay needs each sample's own events), a point < 0, or
            what `as_buffer` refuses (one line).
    """
    buf = as_buffer(buffer)
    if isinstance(point, bool) or not isinstance(point, (int, np.integer)) or point < 0:
        raise UsageError(f"bad value {point!r} for point: expected a sample index >= 0")
    if buf.stores != "mean":
        raise UsageError("a per-pixel view needs a buffer of children means (direct or affine): a "
                         "sequence buffer's replay needs every sample's own events")
    key = ("per_pixel", int(point))
    if key in buf.device:
        return buf.device[key]
    a = buf.arrays
    pixel, size = a["pixel"], buf.width * buf.height
    mine = a["own"] > 0 if "own" in a else None
    counts = np.bincount(pixel if mine is None else pixel[mine], minlength=size)
    if (mine is None and counts.size and counts.min() == counts.max() > point
            and (pixel.size < 2 or bool(np.all(pixel[1:] >= pixel[:-1])))):
        # k camera samples per pixel in pixel order (coverage points): the point-th of each block
        index = np.arange(size, dtype=np.int64) * int(counts[0]) + int(point)
    else:
        candidates = np.arange(pixel.size) if mine is None else np.flatnonzero(mine)
        order = candidates[np.argsort(pixel[candidates], kind="stable")]
        starts = np.cumsum(counts) - counts
        index = order[(starts + point)[counts > point]]
    taken = mi.UInt32(aligned(index, np.uint32))
    names = [k for k in fields_for(buf.stylize, "mean") + (DENOISED, SPREAD) if k in a]
    arrays: dict[str, Any] = {}
    for k in names:
        if k == "pixel" or a.on_host(k):
            arrays[k] = a[k][..., index]
        else:  # on the device: gathered there
            x = field(buf, k)
            arrays[k] = dr.gather(type(x), x, taken)
    dr.eval(*[x for x in arrays.values() if not isinstance(x, np.ndarray)])
    arrays.update({k: a[k] for k in a if k.startswith(PILOT)})
    header = copy.deepcopy(buf.header)
    for k in ("layout", "tiles", "sample_border"):
        header.pop(k, None)
    first = buf.header["passes"][0] if buf.header["passes"] else {"seed": 0}
    header.update(filter="box", passes=[{"spp": 1, "seed": int(first["seed"])}],
                  per_pixel={"point": int(point), "of": buf.camera_samples})
    view = Buffer(header, arrays)
    buf.device[key] = view
    return view


def restyled(buffer: Any, style: str | None = None, estimator: str | None = None,
             inner: Any = None, **params: Any) -> mi.Float:
    """`restyle`'s image left on the device: flat H*W*3 row-major RGB, evaluated.

    Args, Raises: as `restyle`'s.
    """
    buf = as_buffer(buffer)
    slots = prepare_slots(buf, slots_for(buf, style, estimator, inner, **params))
    try:  # θ as the kernel's inputs (`Style.opaque`): a new value reuses the compiled kernel
        img = accumulate(buf, sample_values(buf, [replace(s, style=s.style.opaque())
                                                  for s in slots]))
        dr.eval(img)
    except StyletraceError:
        raise
    except Exception:  # a style that reads a parameter's value on the host: θ as literals
        img = accumulate(buf, sample_values(buf, slots))
        dr.eval(img)
    return img


def restyle(buffer: Any, style: str | None = None, estimator: str | None = None, inner: Any = None,
            **params: Any) -> np.ndarray:
    """The image of the buffer's camera samples with a new style or parameters (module doc).

    Args:
        buffer: a Buffer or its .npz path; style: the new style (None: the recorded one).
        estimator, inner: None: the recorded ones (`slots_for` says what may change).
        params: new parameter values of the changed slots (`changed_owner`).

    Returns:
        H x W x 3 float32, linear.

    Raises:
        UsageError: a change the buffer cannot replay; StyleError, SettingsError: bad values.
    """
    buf = as_buffer(buffer)
    img = restyled(buf, style, estimator, inner, **params)
    return np.asarray(img, dtype=np.float32).reshape(buf.height, buf.width, 3)


__all__ = [
    "restyle",
    "restyled",
    "join",
    "joined",
    "JOIN",
    "finish_slot",
    "finish_spread",
    "SPREAD_NODES",
    "slot_record",
    "slots_for",
    "sample_values",
    "accumulate",
    "device",
    "prepare_slots",
    "as_buffer",
    "replay_lanes",
    "per_pixel",
    "field",
]
