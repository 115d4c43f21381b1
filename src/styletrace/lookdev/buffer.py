"""The expectation buffer: per camera sample, everything a stylized image depends on except θ.

Two kinds (`header["stores"]`): "mean" (`direct`, `affine`: value = L_before + beta g_θ(mean,
vertex)) and "sequence" (the unbiased estimators: the children and uniforms in call order,
`lookdev.sequence`). Arrays per camera sample: pixel, slot, p, n, wo, mean, L_before, beta, depth,
plus pos and own for a non-box filter, or seq_count, seq_kind, child and uniform for a sequence
buffer; the header keeps the passes, tiles, filter and the sensor's to-world matrix. In memory the
arrays are an `Arrays`: Dr.Jit arrays where the recording kernel wrote them, numpy once read. Files
are `.npz`, written atomically. Sizes: `bytes_per_camera_sample` (65 bytes for first_hit); caps
`MAX_CAMERA_SAMPLES`, `MAX_SEQUENCE_CAMERA_SAMPLES`, `MAX_EVENTS_PER_SAMPLE`. Layout in full:
docs/lookdev.md and
docs/design/expectation_buffer.md.
"""
from __future__ import annotations

import json
import os
import tempfile
import zipfile
from collections.abc import MutableMapping
from dataclasses import dataclass, field
from typing import Any, Iterator

import numpy as np

from styletrace.errors import UsageError
from styletrace.images import creation_mode, destination, unwritable_kind

#: the default cap on one buffer's camera samples (the budget's: an expectation render is split
#: within it)
from styletrace.pipeline.budget import MAX_CAMERA_SAMPLES

FORMAT = "styletrace-buffer"
VERSION = 3  # 3: filters other than a box; 2: "sequence" buffers; versions 1 and 2 still read
#: the cap for sequence buffers (256 x 256 at 16 spp): at most 4 + 18 x 64 bytes per camera sample
#: more (13 per child, 5 per uniform, up to MAX_EVENTS_PER_SAMPLE of each)
MAX_SEQUENCE_CAMERA_SAMPLES = 1 << 20
SEQUENCE = ("seq_count", "seq_kind", "child", "uniform")

SCALAR = {"pixel": np.uint32, "slot": np.int8, "depth": np.uint32, "own": np.uint8}
VECTOR = ("p", "n", "wo", "mean", "L_before", "beta")
#: the fields of a buffer recorded with a filter other than a box
FILTERED = ("pos", "own")
_BYTES = {"pixel": 4, "depth": 4, "seq_count": 4, "slot": 1, "own": 1, "pos": 8}


def fields_for(stylize: str, stores: str = "mean", filtered: bool = False) -> tuple[str, ...]:
    """The names of a buffer's per-sample arrays, in order.

    Args:
        stylize: the integrator's stylize mode; "first_object_hit" adds beta and depth.
        stores: "mean" (adds mean) or "sequence" (adds the SEQUENCE arrays).
        filtered: recorded with a filter other than a box (adds the FILTERED arrays).

    Returns:
        The field names.
    """
    base = (("pixel", "slot", "p", "n", "wo") + (("mean",) if stores == "mean" else ())
            + ("L_before",))
    return base + (("beta", "depth") if stylize == "first_object_hit" else ()) + (
        SEQUENCE if stores == "sequence" else ()) + (FILTERED if filtered else ())


def bytes_per_camera_sample(stylize: str, stores: str = "mean", filtered: bool = False) -> int:
    """The bytes per camera sample of a buffer's fixed fields.

    Args:
        stylize, stores, filtered: as for `fields_for`.

    Returns:
        The bytes of the fixed-size fields (a sequence buffer adds its events on top).
    """
    fields = fields_for(stylize, stores, filtered)
    return sum(_BYTES.get(k, 12) for k in fields if k not in SEQUENCE[1:])


def filtered(header: dict) -> bool:
    """Whether a buffer was recorded with a filter other than a box.

    Args:
        header: the buffer's header; its "filter" entry (missing in old buffers: a box).

    Returns:
        True where the filter is no box: the buffer then has `FILTERED`'s arrays.
    """
    spec = header.get("filter")
    return not (spec in (None, "box") or (isinstance(spec, dict) and spec.get("type") == "box"))


#: a denoised buffer's relative uncertainty of D per sample (float32 (N,)): restyles average g over
#: it (`lookdev.restyle.finish_spread`, docs/denoise.md)
SPREAD = "denoise_spread"
#: a denoised buffer's D at each camera sample (float32 (3, N), in place of `mean` when restyling;
#: `denoise.expectation.attach` with k = 0)
DENOISED = "denoised_mean"

#: prefix of the arrays that keep the scene-defaults pilot (`scene.defaults.ScenePilot.records`),
#: so that a restyle resolves a style's 'auto' values exactly as a fresh render of the scene does
PILOT = "pilot_"


#: the host dtype of each array that is not float32 (a Dr.Jit part is converted to it)
HOST_DTYPES = {**SCALAR, "seq_count": np.uint32, "seq_kind": np.uint8}


def _part_length(part) -> int:
    """The samples (last axis) of one part, numpy or Dr.Jit (whose `shape` ends in its width)."""
    return int(part.shape[-1])


def _part_nbytes(key: str, part) -> int:
    if isinstance(part, np.ndarray):
        return int(part.nbytes)
    rows = int(np.prod(part.shape[:-1], dtype=np.int64)) if len(part.shape) > 1 else 1
    return rows * _part_length(part) * np.dtype(HOST_DTYPES.get(key, np.float32)).itemsize


def host_array(key: str, part) -> np.ndarray:
    """One part of a buffer's array as numpy, in the dtype the buffer stores it in.

    Args:
        key: the array's name (its dtype: HOST_DTYPES, else float32).
        part: a numpy array (returned as it is) or a Dr.Jit array: a scalar type (N,) or a vector
            type (2 or 3 rows, N).

    Returns:
        The numpy array, (N,) or (rows, N); a Dr.Jit part is copied (never a view of the device's
        memory, which a write on the host would change).
    """
    if isinstance(part, np.ndarray):
        return part
    dtype = HOST_DTYPES.get(key, np.float32)
    out = np.asarray(part)
    # a vector type's rows are gathered into a new array already; a scalar type's is a view of the
    # device's memory: copied (np.array(part, copy=True) costs 5-50x more for a vector type)
    return out.astype(dtype) if out.ndim == 1 else np.asarray(out, dtype=dtype)


class Arrays(MutableMapping):
    """A buffer's per-sample arrays by name: numpy arrays on the host, each joined on first read.

    An array is kept as the parts it was appended in, pass by pass (`Buffer.append`): numpy arrays,
    or Dr.Jit arrays where the kernel that wrote them left them (`lookdev.record`). Reading an array
    (`arrays[k]`, `items()`, `np.savez(**arrays)`) joins its parts on the host once and keeps the
    result; `parts(k)` gives them as they are, for `lookdev.restyle`'s Dr.Jit copies, so a buffer
    that is only restyled (the denoiser's coverage points) is never copied to the host. Why: at 4M
    samples the host copies cost a second or more (issue 36; docs/design/expectation_buffer.md).

    Args:
        arrays: the initial arrays by name (numpy or Dr.Jit), one part each; None: empty.
    """

    def __init__(self, arrays: dict[str, Any] | None = None):
        self._parts: dict[str, list] = {}
        self._host: dict[str, np.ndarray] = {}
        for k, v in (arrays or {}).items():
            self[k] = v

    def __getitem__(self, key: str) -> np.ndarray:
        if key not in self._host:
            parts = [host_array(key, p) for p in self._parts[key]]
            joined = parts[0] if len(parts) == 1 else np.concatenate(parts, axis=-1)
            self._host[key] = joined
            if all(isinstance(p, np.ndarray) for p in self._parts[key]):
                self._parts[key] = [joined]  # host parts are not kept twice
        return self._host[key]

    def __setitem__(self, key: str, value) -> None:
        self._parts[key] = [value]
        if isinstance(value, np.ndarray):
            self._host[key] = value
        else:
            self._host.pop(key, None)

    def __delitem__(self, key: str) -> None:
        del self._parts[key]
        self._host.pop(key, None)

    def __iter__(self) -> Iterator[str]:
        return iter(list(self._parts))

    def __len__(self) -> int:
        return len(self._parts)

    def __contains__(self, key: object) -> bool:
        return key in self._parts

    def append(self, key: str, value) -> None:
        """Add one pass's part to an array (a new array where `key` has none).

        Args:
            key: the array's name. value: the part, numpy or Dr.Jit, samples on its last axis.
        """
        self._parts.setdefault(key, []).append(value)
        self._host.pop(key, None)

    def parts(self, key: str) -> list:
        """The parts of an array as they were appended (numpy or Dr.Jit), without a copy.

        Args:
            key: the array's name.

        Returns:
            A new list of the parts; one part, numpy, once the array was read on the host.

        Raises:
            KeyError: no such array.
        """
        return list(self._parts[key])

    def on_host(self, key: str) -> bool:
        """Whether reading `key` copies nothing (its one part is numpy, or it was read before).

        Args:
            key: the array's name.

        Returns:
            True where the array is on the host already.

        Raises:
            KeyError: no such array.
        """
        return key in self._host or all(isinstance(p, np.ndarray) for p in self._parts[key])

    def length(self, key: str) -> int:
        """The samples (last axis) of an array, without copying it.

        Args:
            key: the array's name.

        Returns:
            The sum of its parts' lengths.

        Raises:
            KeyError: no such array.
        """
        return sum(_part_length(p) for p in self._parts[key])

    def nbytes(self, key: str) -> int:
        """The bytes an array takes on the host (its dtype there), without copying it.

        Args:
            key: the array's name.

        Returns:
            The bytes.

        Raises:
            KeyError: no such array.
        """
        if key in self._host:
            return int(self._host[key].nbytes)
        return sum(_part_nbytes(key, p) for p in self._parts[key])

    def copy(self) -> "Arrays":
        """A shallow copy: the same parts and host arrays, its own names (a change of one array
        in either leaves the other's alone).

        Returns:
            The new Arrays.
        """
        out = Arrays()
        out._parts = {k: list(v) for k, v in self._parts.items()}
        out._host = dict(self._host)
        return out


@dataclass
class Buffer:
    """An expectation buffer in memory: `header` (JSON-able dict) and `arrays` (`Arrays`: numpy on
    first read, see the module doc; a dict given is wrapped)."""

    header: dict[str, Any]
    arrays: Arrays
    #: Dr.Jit copies of the arrays, made by `lookdev.restyle` on first use and kept for later
    #: restyles
    device: dict[str, Any] = field(default_factory=dict, repr=False, compare=False)
    #: the image rendered while recording (not saved; `restyle` with the recorded style reproduces
    #: it)
    image: Any = field(default=None, repr=False, compare=False)

    def __post_init__(self):
        if not isinstance(self.arrays, Arrays):
            self.arrays = Arrays(self.arrays)

    @property
    def width(self) -> int:
        return int(self.header["width"])

    @property
    def height(self) -> int:
        return int(self.header["height"])

    @property
    def camera_samples(self) -> int:
        """The camera samples it holds (of every pixel and pass)."""
        return self.arrays.length("pixel")

    @property
    def spp(self) -> int:
        """Camera samples per pixel: of every pixel, where a tiled film has a round of tiles under
        way."""
        per_tile = [0] * int(self.header.get("tiles", 1))
        for p in self.header["passes"]:
            per_tile[int(p.get("tile", 0))] += int(p["spp"])
        return min(per_tile)

    @property
    def stylize(self) -> str:
        return self.header["stylize"]

    @property
    def filtered(self) -> bool:
        """Recorded with a filter other than a box: samples are splatted with it
        (`lookdev.film_filter`)."""
        return filtered(self.header)

    @property
    def stores(self) -> str:
        """"mean" (direct / affine) or "sequence" (the children and uniforms in call order)."""
        return self.header.get("stores", "mean")

    @property
    def nbytes(self) -> int:
        """Bytes of the camera samples' arrays (the fixed-size pilot aside: `pilot_nbytes`)."""
        return sum(self.arrays.nbytes(k) for k in self.arrays if not k.startswith(PILOT))

    @property
    def pilot_nbytes(self) -> int:
        return sum(self.arrays.nbytes(k) for k in self.arrays if k.startswith(PILOT))

    def save(self, path: str) -> str:
        """Write the buffer atomically (temporary file, rename), as the images are written.

        Args:
            path: the .npz file (a str or path-like); a symbolic link is written through.

        Returns:
            `path` as a str.

        Raises:
            UsageError: no .npz extension, a path no regular file may replace, a missing folder,
                or a failed write (no temporary file is left).
        """
        path = os.fspath(path)
        if not path.lower().endswith(".npz"):
            raise UsageError(f"bad buffer file {path!r}: the extension must be .npz")
        kind = unwritable_kind(path)
        if kind is not None:
            raise UsageError(f"cannot write {path!r}: it is {kind}; expected a regular file or a "
                             "new name")
        target = destination(path)  # a symbolic link is written through, as the images are
        folder = os.path.dirname(os.path.abspath(target))
        if not os.path.isdir(folder):
            raise UsageError(f"cannot write {path!r}: folder {folder!r} does not exist")
        head = np.frombuffer(json.dumps(self.header).encode("utf-8"), dtype=np.uint8)
        mode = creation_mode(target)
        fd, tmp = tempfile.mkstemp(prefix=".buffer-", suffix=".npz", dir=folder)
        try:
            os.fchmod(fd, mode)
            with os.fdopen(fd, "wb") as f:
                np.savez(f, header=head, **self.arrays)
            os.replace(tmp, target)
        except OSError as exc:
            if os.path.exists(tmp):
                os.unlink(tmp)
            raise UsageError(f"cannot write {path!r}: {exc.strerror or exc}") from None
        return path

    def append(self, arrays: dict[str, np.ndarray], spp: int, seed: int,
               tile: int | None = None) -> None:
        """Add one pass's camera samples, in the order the render loop made them; drops the
        Dr.Jit copies (`device`).

        Args:
            arrays: the pass's arrays by name (`fields_for` this buffer; film pixels, `to_film`),
                numpy or Dr.Jit: kept as they are, joined when read (`Arrays`).
            spp, seed: the pass's camera samples per pixel and its seed.
            tile: the index of the crop window the pass rendered, where the film is rendered in
                tiles (`pipeline.passes`); None otherwise.

        Raises:
            KeyError: an array of `fields_for` missing from `arrays`.
        """
        names = fields_for(self.stylize, self.stores, self.filtered)
        missing = [k for k in names if k not in arrays]
        if missing:
            raise KeyError(missing[0])
        for k in names:
            self.arrays.append(k, arrays[k])
        entry = {"spp": int(spp), "seed": int(seed)}
        if tile is not None:
            entry["tile"] = int(tile)
        if self.filtered:
            entry["samples"] = _part_length(arrays["pixel"])
        self.header["passes"].append(entry)
        self.device.clear()


def load_buffer(path: str) -> Buffer:
    """Read a buffer written by `Buffer.save` (format versions 1 to VERSION).

    Args:
        path: the .npz file (a str or path-like).

    Returns:
        The Buffer: its camera samples' arrays, the pilot's and a denoised render's, if kept.

    Raises:
        UsageError: a missing, unreadable, foreign or newer file, or arrays whose shapes, tiles or
            sample counts disagree (one line).
    """
    path = os.fspath(path)
    if not os.path.isfile(path):
        raise UsageError(f"buffer file {path!r} does not exist")
    # np.load reads any other file as a pickle and answers with its advice on pickles
    foreign = UsageError(f"{path!r} is not a styletrace buffer: expected the .npz file of "
                         f"`styletrace render --buffer` or Buffer.save")
    if not zipfile.is_zipfile(path):
        raise foreign
    try:
        with np.load(path, allow_pickle=False) as z:
            if "header" not in z.files:
                raise foreign
            header = json.loads(bytes(z["header"]).decode("utf-8"))
            if not isinstance(header, dict) or header.get("format") != FORMAT:
                raise foreign
            if header.get("version") not in range(1, VERSION + 1):
                raise UsageError(
                    f"buffer file {path!r} has format version {header.get('version')!r}; this "
                    f"styletrace reads version {VERSION} and earlier"
                )
            arrays = {k: z[k] for k in fields_for(header["stylize"], header.get("stores", "mean"),
                                                  filtered(header))}
            pilot = {k: z[k] for k in z.files if k.startswith(PILOT)}
            # docs/denoise.md
            denoised = {k: z[k] for k in z.files if k in (DENOISED, SPREAD)}
    except UsageError:
        raise
    except (OSError, ValueError, KeyError, EOFError) as exc:
        raise UsageError(f"cannot read buffer file {path!r}: {exc}") from None
    n = arrays["pixel"].shape[0]
    if "seq_kind" in arrays:
        events, children = int(arrays["seq_count"].sum()), int(arrays["seq_kind"].sum())
        seq = {"seq_count": (n,), "seq_kind": (events,), "child": (3, children),
               "uniform": (events - children,)}
    for k, a in arrays.items():
        want = (seq[k] if k in SEQUENCE else (n,) if k in SCALAR else (2, n) if k == "pos"
                else (3, n))
        if a.shape != want:
            raise UsageError(f"cannot read buffer file {path!r}: array {k!r} has shape {a.shape}, "
                             f"expected {want}")
    if len({a.shape[0] for a in pilot.values()}) > 1:
        raise UsageError(f"cannot read buffer file {path!r}: its pilot arrays differ in length")
    tiles = header.get("tiles", 1)
    if (
        not isinstance(tiles, int)
        or tiles < 1
        or any(
            not isinstance(p.get("tile", 0), int) or not 0 <= p.get("tile", 0) < tiles
            for p in header["passes"]
        )
    ):
        raise UsageError(f"cannot read buffer file {path!r}: its passes name tiles outside its "
                         f"{tiles!r} tiles")
    if filtered(header) and sum(int(p.get("samples", -1)) for p in header["passes"]) != n:
        raise UsageError(f"cannot read buffer file {path!r}: its passes do not add up to its {n} "
                         f"camera samples")
    for k, a in denoised.items():
        want = (n,) if k == SPREAD else (3, n)
        if a.shape != want:
            raise UsageError(f"cannot read buffer file {path!r}: array {k!r} has shape {a.shape}, "
                             f"expected {want}")
    return Buffer(header, {**arrays, **pilot, **denoised})


def check_buffer_path(path: str) -> None:
    """Check, before the render, that the buffer can be written to `path`.

    Args:
        path: the buffer file to write.

    Raises:
        UsageError: no .npz extension, or a path `images.check_target` refuses (one line).
    """
    if not path.lower().endswith(".npz"):
        raise UsageError(f"bad buffer file {path!r}: the extension must be .npz")
    from styletrace.images import check_target
    check_target(path)  # before the render: the buffer is written after it


__all__ = [
    "Buffer",
    "Arrays",
    "host_array",
    "load_buffer",
    "check_buffer_path",
    "SPREAD",
    "DENOISED",
    "FORMAT",
    "VERSION",
    "MAX_CAMERA_SAMPLES",
    "MAX_SEQUENCE_CAMERA_SAMPLES",
    "fields_for",
    "bytes_per_camera_sample",
    "filtered",
    "FILTERED",
]
