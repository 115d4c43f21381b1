"""Writing rendered images: EXR as linear float32, PNG as sRGB 8-bit; atomic and checked.

    write_image(img, "out.png")              # H x W x 3 linear -> file; OSError if it cannot
    write_image(y, "out.exr", "luminance")   # the film's own pixel format
    save_safely(img, "out.exr")              # never loses the render: falls back to a temporary EXR
    nonfinite_pixels(img), mse(img, reference)

A write never leaves a truncated file where a valid one was (temporary file, size check, fsync,
rename). PNG values are clamped to [0, 1] first (NaN -> 0, +inf -> 1). `encode_plain` encodes with
numpy and zlib alone, for the interrupted render. Rationale: docs/design/atomic_image_writes.md.
"""
from __future__ import annotations

import os
import stat
import struct
import sys
import tempfile
import zlib

import numpy as np

from styletrace.cryptomatte import exr_metadata
from styletrace.errors import UsageError

IMAGE_TYPES = (".exr", ".png")


def nonfinite_pixels(image) -> int:
    """Count the pixels with a NaN or infinite channel.

    Args:
        image: H x W x C array-like (the last axis holds the channels).

    Returns:
        How many pixels have at least one non-finite channel.
    """
    arr = np.asarray(image)
    return int(np.count_nonzero(~np.isfinite(arr).all(axis=-1)))


def mse(image, reference) -> float:
    """Mean squared error of two images, in float64.

    Args:
        image, reference: array-likes of one shape (or shapes numpy broadcasts together).

    Returns:
        The mean of the squared differences; inf or NaN when either image has non-finite pixels
        (numpy's warnings about that are silenced, not sent to stderr).
    """
    # inf or NaN is the honest answer for such images: no warning on stderr
    with np.errstate(over="ignore", invalid="ignore"):
        return float(np.mean((np.asarray(image, dtype=np.float64) - reference) ** 2))


def srgb8(image) -> np.ndarray:
    """Encode linear radiance as sRGB 8 bit, clamped first (NaN -> 0, +inf -> 1, -inf -> 0).

    Args:
        image: array-like of linear values, any shape.

    Returns:
        uint8 array of the same shape: the sRGB transfer function of the values clamped to [0, 1].
    """
    x = np.nan_to_num(np.asarray(image, dtype=np.float32), nan=0.0, posinf=1.0, neginf=0.0)
    x = np.clip(x, 0.0, 1.0)  # before the power, so that no negative base reaches it
    enc = np.where(x <= 0.0031308, 12.92 * x, 1.055 * np.power(x, 1 / 2.4) - 0.055)
    return np.round(enc * 255.0).astype(np.uint8)


#: a film's pixel format (as `hdrfilm` names it, or as its description shows it) -> Bitmap pixel
#: format
PIXEL_FORMATS = {
    "rgb": "RGB",
    "rgba": "RGBA",
    "luminance": "Y",
    "y": "Y",
    "luminance_alpha": "YA",
    "ya": "YA",
    "xyz": "XYZ",
    "xyza": "XYZA",
}


def bitmap_format(pixel_format: str, channels: int) -> str:
    """The Bitmap pixel format name of a film's pixel format.

    Args:
        pixel_format: a key of PIXEL_FORMATS (any case): rgb, rgba, luminance or y, ya, xyz, ...
        channels: the image's channel count, which must match the format's.

    Returns:
        'RGB', 'RGBA', 'Y', 'YA', 'XYZ' or 'XYZA'.

    Raises:
        ValueError: an unknown pixel format, or a channel count the format does not have.
    """
    name = PIXEL_FORMATS.get(pixel_format.lower())
    if name is None:
        raise ValueError(f"unknown pixel format {pixel_format!r}: expected one of "
                         f"{', '.join(PIXEL_FORMATS)}")
    if len(name) != channels:
        raise ValueError(f"an image of {channels} channel(s) is not in pixel format "
                         f"{pixel_format!r}")
    return name


def check_format(pixel_format: str, ext: str) -> None:
    """Refuse a PNG of an XYZ film: XYZ has no sRGB encoding, so it is written as EXR only.

    Args:
        pixel_format: the film's pixel format (a key of PIXEL_FORMATS, any case).
        ext: the output's extension, lower case with its dot ('.png', '.exr').

    Raises:
        ValueError: an xyz or xyza format with ext '.png'.
    """
    if PIXEL_FORMATS.get(pixel_format.lower(), "").startswith("XYZ") and ext == ".png":
        raise ValueError(
            f"the film's pixel_format is {pixel_format!r}: XYZ images are written as .exr only "
            f'(or set pixel_format="rgb" for a .png)'
        )


def encode(image, ext: str, pixel_format: str = "rgb") -> bytes:
    """Encode an image in memory with Mitsuba's Bitmap (chooses the backend first).

    Args:
        image: H x W x C (or H x W for one channel) linear pixels in the film's `pixel_format`.
        ext: '.exr' (linear float32) or '.png' (sRGB 8 bit; an alpha channel stays linear).
        pixel_format: rgb, rgba, luminance (Y), luminance_alpha, xyz or xyza.

    Returns:
        The file's contents.

    Raises:
        ValueError: an unknown format or extension, a wrong channel count, XYZ as PNG.
    """
    import mitsuba as mi

    from styletrace.jit import backend
    backend()
    image = np.asarray(image)
    name = bitmap_format(pixel_format, image.shape[-1] if image.ndim == 3 else 1)
    check_format(pixel_format, ext)
    if ext == ".png":
        data, fmt = srgb8(image), mi.Bitmap.FileFormat.PNG
        if name.endswith("A"):  # coverage is no colour: quantized linearly
            data[..., -1] = np.round(
                np.clip(np.nan_to_num(image[..., -1]), 0.0, 1.0) * 255.0).astype(np.uint8)
    elif ext == ".exr":
        data, fmt = np.ascontiguousarray(image, dtype=np.float32), mi.Bitmap.FileFormat.OpenEXR
    else:
        raise ValueError(f"unknown image type {ext!r}: expected one of {', '.join(IMAGE_TYPES)}")
    bmp = mi.Bitmap(np.ascontiguousarray(data), pixel_format=getattr(mi.Bitmap.PixelFormat, name))
    if ext == ".png":
        bmp.set_srgb_gamma(True)
    stream = mi.MemoryStream()
    bmp.write(stream, fmt)
    del bmp
    return stream.raw_buffer()


def _exr_attribute(name: str, kind: str, value: bytes) -> bytes:
    return name.encode() + b"\0" + kind.encode() + b"\0" + struct.pack("<i", len(value)) + value


def _plain_exr(data: np.ndarray, names: list[str], strings: dict | None = None) -> bytes:
    """A single-part scanline OpenEXR file, float32 channels, no compression, one line per block,
    `strings` as string attributes of its header. The format stores channels sorted by name,
    each line channel after channel."""
    height, width = data.shape[:2]
    order = sorted(range(len(names)), key=lambda i: names[i])
    chlist = b"".join(names[i].encode() + b"\0" + struct.pack("<iB3xii", 2, 0, 1, 1)
                      for i in order) + b"\0"
    box = struct.pack("<iiii", 0, 0, width - 1, height - 1)
    header = (b"\x76\x2f\x31\x01" + struct.pack("<i", 2)
              + _exr_attribute("channels", "chlist", chlist)
              + _exr_attribute("compression", "compression", b"\0")
              + _exr_attribute("dataWindow", "box2i", box)
              + _exr_attribute("displayWindow", "box2i", box)
              + _exr_attribute("lineOrder", "lineOrder", b"\0")
              + _exr_attribute("pixelAspectRatio", "float", struct.pack("<f", 1.0))
              + _exr_attribute("screenWindowCenter", "v2f", struct.pack("<ff", 0.0, 0.0))
              + _exr_attribute("screenWindowWidth", "float", struct.pack("<f", 1.0))
              + b"".join(_exr_attribute(k, "string", v.encode("utf-8"))
                         for k, v in (strings or {}).items()) + b"\0")
    # every line: y, byte count, then the channels' values (sorted channel order, little-endian
    # float32)
    lines = np.ascontiguousarray(data[..., order].transpose(0, 2, 1),
                                 dtype="<f4").reshape(height, -1)
    line_bytes = lines.shape[1] * 4
    start = len(header) + 8 * height
    offsets = np.arange(height, dtype="<u8") * (8 + line_bytes) + start
    prefix = np.zeros((height, 2), dtype="<i4")
    prefix[:, 0], prefix[:, 1] = np.arange(height), line_bytes
    blocks = np.concatenate([prefix.view(np.uint8), lines.view(np.uint8)], axis=1)
    return header + offsets.tobytes() + blocks.tobytes()


def _png_chunk(kind: bytes, body: bytes) -> bytes:
    return (struct.pack(">I", len(body)) + kind + body
            + struct.pack(">I", zlib.crc32(kind + body) & 0xFFFFFFFF))


def _plain_png(data: np.ndarray) -> bytes:
    """An 8-bit PNG (grey, grey+alpha, RGB or RGBA by the channel count) tagged sRGB; filter 0 per
    line."""
    height, width, channels = data.shape
    colour = {1: 0, 2: 4, 3: 2, 4: 6}[channels]
    rows = np.concatenate([np.zeros((height, 1), np.uint8), data.reshape(height, -1)], axis=1)
    return (
        b"\x89PNG\r\n\x1a\n"
        + _png_chunk(b"IHDR", struct.pack(">IIBBBBB", width, height, 8, colour, 0, 0, 0))
        + _png_chunk(b"sRGB", b"\0")
        + _png_chunk(b"IDAT", zlib.compress(rows.tobytes(), 6))
        + _png_chunk(b"IEND", b"")
    )


def encode_plain(image, ext: str, pixel_format: str = "rgb", aovs: dict | None = None) -> bytes:
    """Encode as `encode` (`encode_with_aovs` with `aovs`) does, the same pixel values, without
    Mitsuba: for a thread that must write while a kernel runs.

    Args:
        image, ext, pixel_format: as for `encode`.
        aovs: the error AOVs and data passes to add as EXR channels (`with_aovs`), or None.

    Returns:
        The file's contents: an uncompressed float32 EXR, or a PNG of `srgb8`'s bytes.

    Raises:
        ValueError: as `encode`; also aovs with a '.png'.
    """
    image = np.asarray(image, dtype=np.float32)
    if image.ndim == 2:
        image = image[..., None]
    name = bitmap_format(pixel_format, image.shape[-1])
    check_format(pixel_format, ext)
    if ext == ".png":
        if aovs is not None:
            raise ValueError(f"error AOVs and data passes are written to .exr files only, not "
                             f"{ext!r}")
        data = srgb8(image)
        if name.endswith("A"):  # as `encode`: coverage is quantized linearly
            data[..., -1] = np.round(
                np.clip(np.nan_to_num(image[..., -1]), 0.0, 1.0) * 255.0).astype(np.uint8)
        return _plain_png(data)
    if ext != ".exr":
        raise ValueError(f"unknown image type {ext!r}: expected one of {', '.join(IMAGE_TYPES)}")
    data, names = with_aovs(image, list(name), aovs or {})
    return _plain_exr(data, names, header_of(aovs))


#: the EXR channels of the error AOVs, after the image's own (R, G, B[, A]); see `api.Progress.aovs`
AOV_CHANNELS = (("variance", ("variance.R", "variance.G", "variance.B")), ("bias", ("bias",)),
                ("children", ("children",)))


#: with denoising on (docs/denoise.md) the AOVs describe the noisy render and say so;
#: `denoise_change` is what the denoiser changed. Only the keys present are written.
DENOISED_AOV_CHANNELS = (
    ("noisy_variance", ("noisy_variance.R", "noisy_variance.G", "noisy_variance.B")),
    ("noisy_bias", ("noisy_bias",)),
    ("children", ("children",)),
    ("denoise_change", ("denoise_change.R", "denoise_change.G", "denoise_change.B")),
)


#: the data passes (`kernel.data_passes`: docs/passes.md), after the AOVs, under Blender's pass and
#: channel names (a multilayer reader sees the passes under Cycles' names). Only the keys
#: present are written.
DATA_CHANNELS = (("depth", ("Depth.Z",)), ("normal", ("Normal.X", "Normal.Y", "Normal.Z")),
                 ("vector", ("Vector.X", "Vector.Y", "Vector.Z", "Vector.W")),
                 ("position", ("Position.X", "Position.Y", "Position.Z")),
                 ("uv", ("UV.U", "UV.V", "UV.A")), ("mist", ("Mist.Z",)),
                 ("object_index", ("Object Index.X",)), ("material_index", ("Material Index.X",)),
                 ("albedo", ("Denoising Albedo.R", "Denoising Albedo.G", "Denoising Albedo.B")),
                 ("emission", ("Emission.R", "Emission.G", "Emission.B")),
                 # Cycles' names: the standard's lower-case channels, two ranks to a layer
                 *((key, tuple(f"{kind}{k:02d}.{c}" for k in range(3) for c in "rgba"))
                   for key, kind in (("crypto_object", "CryptoObject"),
                                     ("crypto_material", "CryptoMaterial"))))
#: the data passes' entry of the Cryptomatte manifests ({type name: {name: hex}}), written as the
#: standard's EXR header attributes (`cryptomatte.exr_metadata`)
MANIFEST = "manifest"


def header_of(aovs: dict | None) -> dict[str, str]:
    """The EXR header attributes the channels bring: the Cryptomatte types' metadata.

    Args:
        aovs: the error AOVs and data passes by key, or None.

    Returns:
        {attribute name: string value}; empty without a Cryptomatte manifest.
    """
    return exr_metadata((aovs or {}).get(MANIFEST) or {})


def with_aovs(image: np.ndarray, names: list[str], aovs: dict) -> tuple[np.ndarray, list[str]]:
    """Lay out an image, its error AOVs and its data passes as both EXR writers write them.

    Args:
        image: H x W x C pixels; names: its channel names ('R', 'G', 'B', ...).
        aovs: H x W (x k) arrays by key: with 'variance', every key of AOV_CHANNELS; else the
            keys of DENOISED_AOV_CHANNELS present; then the keys of DATA_CHANNELS present. Empty:
            the image alone.

    Returns:
        (one float32 H x W x C' array, its channel names): the image's channels, then the AOVs',
        then the data passes'.

    Raises:
        KeyError: a key of AOV_CHANNELS missing where 'variance' is given.
    """
    layers = [image]
    table = (list(AOV_CHANNELS) if "variance" in aovs
             else [(k, c) for k, c in DENOISED_AOV_CHANNELS if k in aovs])
    table += [(k, c) for k, c in DATA_CHANNELS if k in aovs]
    for key, channels in table if aovs else ():
        arr = np.asarray(aovs[key], dtype=np.float32)
        layers.append(arr.reshape(arr.shape[:2] + (len(channels),)))
        names = names + list(channels)
    return np.ascontiguousarray(np.concatenate(layers, axis=-1)), names


def encode_with_aovs(image, aovs: dict, pixel_format: str = "rgb") -> bytes:
    """Encode a float32 EXR of the image and its error AOVs with Mitsuba (PNG has no room for
    AOVs: the front ends refuse aovs with a PNG output).

    Args:
        image, pixel_format: H x W x C linear pixels, and their film's format (see `encode`).
        aovs: the error AOVs and data passes by key, laid out after the image's channels
            (`with_aovs`).

    Returns:
        The EXR file's contents.

    Raises:
        ValueError: an unknown pixel format, or a channel count it does not have.
    """
    import mitsuba as mi

    from styletrace.jit import backend
    backend()
    image = np.asarray(image, dtype=np.float32)
    data, names = with_aovs(image, list(bitmap_format(pixel_format, image.shape[-1])), aovs)
    bmp = mi.Bitmap(data, pixel_format=mi.Bitmap.PixelFormat.MultiChannel, channel_names=names)
    metadata = bmp.metadata()
    for key, value in header_of(aovs).items():  # the OpenEXR writer stores them as strings
        metadata[key] = value
    stream = mi.MemoryStream()
    bmp.write(stream, mi.Bitmap.FileFormat.OpenEXR)
    del bmp
    return stream.raw_buffer()


def creation_mode(path: str) -> int:
    """The permission bits a file written to `path` should get.

    A temporary file is created 0o600, which a rename would keep: the caller sets these instead.

    Args:
        path: the destination.

    Returns:
        The mode bits of the file it replaces, else what `open` gives a new file (0o666 less the
        umask).
    """
    try:
        return os.stat(path).st_mode & 0o7777
    except OSError:
        umask = os.umask(0)
        os.umask(umask)
        return 0o666 & ~umask


def destination(path: str) -> str:
    """Where a write of `path` lands, so that the rename replaces a link's target, not the link.

    Args:
        path: the destination as given.

    Returns:
        `path` itself, or for a symbolic link its final target (links followed to the end).
    """
    return os.path.realpath(path) if os.path.islink(path) else path


def unwritable_kind(path: str) -> str | None:
    """Why `path` cannot be replaced by renaming a new file over it. Nothing is opened: a fifo or
    a device is only looked at (stat).

    Args:
        path: the destination as given (links are followed).

    Returns:
        None for a regular file, a name not yet taken, or a link to either; else what it is ("a
        folder", "a character device", ..., "not a usable path (reason)").
    """
    try:
        mode = os.stat(path).st_mode  # follows links
    except FileNotFoundError:
        return None  # new, or a link to a name not yet taken (its target is created)
    except OSError as exc:  # a link loop (ELOOP), a path through a file (ENOTDIR), ...
        return f"not a usable path ({exc.strerror})"
    if stat.S_ISREG(mode):
        return None
    for test, kind in (
        (stat.S_ISDIR, "a folder"),
        (stat.S_ISCHR, "a character device"),
        (stat.S_ISBLK, "a block device"),
        (stat.S_ISFIFO, "a fifo"),
        (stat.S_ISSOCK, "a socket"),
    ):
        if test(mode):
            return kind
    return "not a regular file"


def write_bytes_atomically(data: bytes, path: str) -> None:
    """Write bytes atomically: a temporary file in the same folder, full write checked, fsync,
    then os.replace over `path` (and an fsync of the folder where it can be opened).

    Args:
        data: the file's contents.
        path: the destination; a symbolic link is written through: the temporary file goes beside
            its target and replaces it (`destination`), so the link keeps pointing there.

    Raises:
        OSError: `path` is no regular file (`unwritable_kind`: /dev/null, a fifo, a folder; left
            untouched, since a rename would replace it), or the write failed or fell short (the
            temporary file is removed).
    """
    kind = unwritable_kind(path)
    if kind is not None:
        raise OSError(f"{path!r} is {kind}: only a regular file (or a new name) can be replaced "
                      "atomically")
    path = destination(path)
    folder = os.path.dirname(os.path.abspath(path))
    mode = creation_mode(path)
    fd, tmp = tempfile.mkstemp(prefix="." + os.path.basename(path) + ".", suffix=".part",
                               dir=folder)
    try:
        os.fchmod(fd, mode)
        with os.fdopen(fd, "wb") as f:
            written = f.write(data)
            f.flush()
            os.fsync(f.fileno())
            size = os.fstat(f.fileno()).st_size
        if written != len(data) or size != len(data):
            raise OSError(f"short write: {size} of {len(data)} bytes reached the disk")
        os.replace(tmp, path)
    except BaseException:
        try:
            os.remove(tmp)
        except OSError:
            pass
        raise
    try:  # make the rename itself durable; not every file system lets a folder be opened
        dfd = os.open(folder, os.O_RDONLY)
        try:
            os.fsync(dfd)
        finally:
            os.close(dfd)
    except OSError:
        pass


def write_image(image, path: str, pixel_format: str = "rgb", aovs: dict | None = None,
                plain: bool = False) -> None:
    """Write `image` atomically: EXR as linear float32, PNG as sRGB 8 bit, clamped.

    Args:
        image: H x W x C linear pixels.
        path: the destination; its extension chooses the format.
        pixel_format: the film's pixel format (see `encode`).
        aovs: the error AOVs and data passes as extra channels (EXR only), or None.
        plain: encode with `encode_plain` (no Mitsuba: a kernel may be running).

    Raises:
        OSError: the file cannot be written (`write_bytes_atomically`).
        ValueError: AOVs for a format other than EXR, or a format `encode` refuses.
    """
    ext = os.path.splitext(path)[1].lower()
    if plain:
        write_bytes_atomically(encode_plain(image, ext, pixel_format, aovs), path)
        return
    if aovs is not None:
        if ext != ".exr":
            raise ValueError(f"error AOVs and data passes are written to .exr files only, not "
                             f"{ext!r}")
        write_bytes_atomically(encode_with_aovs(image, aovs, pixel_format), path)
        return
    write_bytes_atomically(encode(image, ext, pixel_format), path)


def save_safely(image, path: str, pixel_format: str = "rgb", aovs: dict | None = None,
                plain: bool = False) -> str:
    """Write `image`; if that fails, keep it in a temporary EXR instead of losing it.

    Args:
        image, path, pixel_format, aovs, plain: as for `write_image`.

    Returns:
        The path written: `path`, or the temporary EXR's.

    Raises:
        Exception: the fallback failed too (no empty temporary file is left behind).
    """
    try:
        write_image(image, path, pixel_format, aovs, plain)
        return path
    except Exception as exc:  # the render must survive an I/O failure
        fd, fallback = tempfile.mkstemp(prefix="styletrace-", suffix=".exr")
        os.close(fd)
        try:
            write_image(image, fallback, pixel_format, aovs, plain)
        except BaseException:
            os.remove(fallback)
            raise
        reason = str(exc).replace("\n", " ")
        print(f"styletrace: could not write {path!r} ({reason}); saved the "
              f"render to {fallback}", file=sys.stderr)
        return fallback



def check_target(path: str) -> None:
    """Check, before a render, that `write_bytes_atomically` can replace `path`.

    Args:
        path: the output: a regular file or a new name in an existing, writable folder; a symbolic
            link counts as its target, which is where the file goes (the link stays).

    Raises:
        UsageError: a device (/dev/null too: the rename would replace the device node), fifo,
            socket or folder (all left untouched), a missing folder, no write permission, or a
            folder that refuses the temporary file the write makes (tried: created and removed).
    """
    kind = unwritable_kind(path)
    if kind is not None:
        via = f" (a link to {os.path.realpath(path)!r})" if os.path.islink(path) else ""
        raise UsageError(f"cannot write {path!r}: it is {kind}{via}; expected a regular file or a "
                         "new name")
    target = destination(path)
    folder = os.path.dirname(os.path.abspath(target))
    if not os.path.isdir(folder):
        raise UsageError(f"cannot write {path!r}: folder {folder!r} does not exist")
    if not os.access(folder, os.W_OK) or (os.path.exists(target)
                                          and not os.access(target, os.W_OK)):
        raise UsageError(f"cannot write {path!r}: permission denied")
    check_folder_takes_files(folder, path, "." + os.path.basename(target) + ".")


def check_folder_takes_files(folder: str, path: str, prefix: str = ".styletrace.") -> None:
    """Check that a new file can be made in `folder` by making one (a temporary `.part` file, as
    `write_bytes_atomically` makes) and removing it.

    Permission bits do not bind root, and /sys, /proc or a read-only mount pass `os.access` for
    it; only an attempt tells.

    Args:
        folder: an existing folder. path: the output named in the error. prefix: the temporary
            file's name prefix.

    Raises:
        UsageError: the folder refuses the file (one line naming `path` and the folder).
    """
    try:
        fd, tmp = tempfile.mkstemp(prefix=prefix, suffix=".part", dir=folder)
    except OSError as exc:
        raise UsageError(f"cannot write {path!r}: folder {folder!r} refuses new files "
                         f"({exc.strerror or exc})") from None
    os.close(fd)
    os.remove(tmp)


__all__ = [
    "check_target",
    "check_folder_takes_files",
    "IMAGE_TYPES",
    "PIXEL_FORMATS",
    "AOV_CHANNELS",
    "DATA_CHANNELS",
    "bitmap_format",
    "check_format",
    "nonfinite_pixels",
    "srgb8",
    "encode",
    "encode_plain",
    "encode_with_aovs",
    "destination",
    "unwritable_kind",
    "write_bytes_atomically",
    "write_image",
    "save_safely",
]
