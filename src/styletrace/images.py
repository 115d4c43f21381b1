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

from styletrace.errors import UsageError

IMAGE_TYPES = (".exr", ".png")


def nonfinite_pixels(image) -> int:
    """Pixels with a NaN or infinite channel."""
    arr = np.asarray(image)
    return int(np.count_nonzero(~np.isfinite(arr).all(axis=-1)))


def mse(image, reference) -> float:
    """Mean squared error; inf or NaN when either image has non-finite pixels (that is the honest
    answer, so numpy's warnings about it are silenced here rather than sent to stderr)."""
    with np.errstate(over="ignore", invalid="ignore"):
        return float(np.mean((np.asarray(image, dtype=np.float64) - reference) ** 2))


def srgb8(image) -> np.ndarray:
    """Linear radiance -> sRGB-encoded uint8: NaN -> 0, +inf -> 1 (255), everything clamped to [0,
    1]."""
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
    """The Bitmap pixel format name ('RGB', 'Y', 'XYZA', ...) of an image with `channels`
    channels."""
    name = PIXEL_FORMATS.get(pixel_format.lower())
    if name is None:
        raise ValueError(f"unknown pixel format {pixel_format!r}: expected one of "
                         f"{', '.join(PIXEL_FORMATS)}")
    if len(name) != channels:
        raise ValueError(f"an image of {channels} channel(s) is not in pixel format "
                         f"{pixel_format!r}")
    return name


def check_format(pixel_format: str, ext: str) -> None:
    """XYZ has no sRGB encoding: such a film is written as EXR only (ValueError otherwise)."""
    if PIXEL_FORMATS.get(pixel_format.lower(), "").startswith("XYZ") and ext == ".png":
        raise ValueError(
            f"the film's pixel_format is {pixel_format!r}: XYZ images are written as .exr only "
            f'(or set pixel_format="rgb" for a .png)'
        )


def encode(image, ext: str, pixel_format: str = "rgb") -> bytes:
    """The file contents of `image` as `.exr` (linear float32) or `.png` (sRGB 8 bit; alpha stays
    linear). `image` is H x W x C in the film's `pixel_format`: rgb, rgba, luminance (Y),
    luminance_alpha, xyz, xyza."""
    import mitsuba as mi

    from styletrace.jit import backend
    backend()
    image = np.asarray(image)
    name = bitmap_format(pixel_format, image.shape[-1] if image.ndim == 3 else 1)
    check_format(pixel_format, ext)
    if ext == ".png":
        data, fmt = srgb8(image), mi.Bitmap.FileFormat.PNG
        if name.endswith("A"):  # coverage is no colour: quantized linearly
            data[..., -1] = np.round(np.clip(np.nan_to_num(image[..., -1]), 0.0, 1.0) * 255.0).astype(np.uint8)
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


def _plain_exr(data: np.ndarray, names: list[str]) -> bytes:
    """A single-part scanline OpenEXR file, float32 channels, no compression, one line per block.
    The format stores channels sorted by name, each line channel after channel."""
    height, width = data.shape[:2]
    order = sorted(range(len(names)), key=lambda i: names[i])
    chlist = b"".join(names[i].encode() + b"\0" + struct.pack("<iB3xii", 2, 0, 1, 1) for i in order) + b"\0"
    box = struct.pack("<iiii", 0, 0, width - 1, height - 1)
    header = (b"\x76\x2f\x31\x01" + struct.pack("<i", 2)
              + _exr_attribute("channels", "chlist", chlist)
              + _exr_attribute("compression", "compression", b"\0")
              + _exr_attribute("dataWindow", "box2i", box)
              + _exr_attribute("displayWindow", "box2i", box)
              + _exr_attribute("lineOrder", "lineOrder", b"\0")
              + _exr_attribute("pixelAspectRatio", "float", struct.pack("<f", 1.0))
              + _exr_attribute("screenWindowCenter", "v2f", struct.pack("<ff", 0.0, 0.0))
              + _exr_attribute("screenWindowWidth", "float", struct.pack("<f", 1.0)) + b"\0")
    # every line: y, byte count, then the channels' values (sorted channel order, little-endian
    # float32)
    lines = np.ascontiguousarray(data[..., order].transpose(0, 2, 1), dtype="<f4").reshape(height, -1)
    line_bytes = lines.shape[1] * 4
    start = len(header) + 8 * height
    offsets = np.arange(height, dtype="<u8") * (8 + line_bytes) + start
    prefix = np.zeros((height, 2), dtype="<i4")
    prefix[:, 0], prefix[:, 1] = np.arange(height), line_bytes
    blocks = np.concatenate([prefix.view(np.uint8), lines.view(np.uint8)], axis=1)
    return header + offsets.tobytes() + blocks.tobytes()


def _png_chunk(kind: bytes, body: bytes) -> bytes:
    return struct.pack(">I", len(body)) + kind + body + struct.pack(">I", zlib.crc32(kind + body) & 0xFFFFFFFF)


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
    """What `encode` (`encode_with_aovs` with `aovs`) writes, the same pixel values, without
    Mitsuba: for a thread that must write while a kernel runs. EXR: float32, uncompressed; PNG:
    `srgb8`'s bytes."""
    image = np.asarray(image, dtype=np.float32)
    if image.ndim == 2:
        image = image[..., None]
    name = bitmap_format(pixel_format, image.shape[-1])
    check_format(pixel_format, ext)
    if ext == ".png":
        if aovs is not None:
            raise ValueError(f"error AOVs are written to .exr files only, not {ext!r}")
        data = srgb8(image)
        if name.endswith("A"):  # as `encode`: coverage is quantized linearly
            data[..., -1] = np.round(np.clip(np.nan_to_num(image[..., -1]), 0.0, 1.0) * 255.0).astype(np.uint8)
        return _plain_png(data)
    if ext != ".exr":
        raise ValueError(f"unknown image type {ext!r}: expected one of {', '.join(IMAGE_TYPES)}")
    data, names = with_aovs(image, list(name), aovs or {})
    return _plain_exr(data, names)


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


def with_aovs(image: np.ndarray, names: list[str], aovs: dict) -> tuple[np.ndarray, list[str]]:
    """The image's channels (`names`) followed by the AOVs present in `aovs` (`AOV_CHANNELS`, or
    with denoising `DENOISED_AOV_CHANNELS`), as one float32 H x W x C array and its channel names:
    what both EXR writers lay out."""
    layers = [image]
    table = AOV_CHANNELS if "variance" in aovs else [(k, c) for k, c in DENOISED_AOV_CHANNELS if k in aovs]
    for key, channels in table if aovs else ():
        arr = np.asarray(aovs[key], dtype=np.float32)
        layers.append(arr.reshape(arr.shape[:2] + (len(channels),)))
        names = names + list(channels)
    return np.ascontiguousarray(np.concatenate(layers, axis=-1)), names


def encode_with_aovs(image, aovs: dict, pixel_format: str = "rgb") -> bytes:
    """A multi-channel float32 EXR: the image's channels (R, G, B[, A]) and then the error AOVs
    under the names of `AOV_CHANNELS`. (PNG has no room for them: the front ends refuse aovs with a
    PNG output.)"""
    import mitsuba as mi

    from styletrace.jit import backend
    backend()
    image = np.asarray(image, dtype=np.float32)
    data, names = with_aovs(image, list(bitmap_format(pixel_format, image.shape[-1])), aovs)
    bmp = mi.Bitmap(data, pixel_format=mi.Bitmap.PixelFormat.MultiChannel, channel_names=names)
    stream = mi.MemoryStream()
    bmp.write(stream, mi.Bitmap.FileFormat.OpenEXR)
    del bmp
    return stream.raw_buffer()


def creation_mode(path: str) -> int:
    """The permission bits `path` should get: those of the file it replaces, else what `open` would
    give a new file (0o666 less the umask). A temporary file is created 0o600, which a rename would
    keep."""
    try:
        return os.stat(path).st_mode & 0o7777
    except OSError:
        umask = os.umask(0)
        os.umask(umask)
        return 0o666 & ~umask


def destination(path: str) -> str:
    """Where a write of `path` lands: `path` itself, or for a symbolic link its final target (a link
    to a link is followed to the end), so that the rename replaces the target and the link stays a
    link."""
    return os.path.realpath(path) if os.path.islink(path) else path


def unwritable_kind(path: str) -> str | None:
    """Why `path` cannot be replaced by a rename of a new file ("a folder", "a character device",
    ...), or
    None: a regular file, a name not yet taken, or a link to either. Nothing is opened: a fifo or a
    device is only looked at (stat)."""
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
    """Temporary file in the same folder, full write checked, fsync, then os.replace over `path`. A
    symbolic link is written through: the temporary file goes beside its target and is renamed over
    the target (`destination`), so the link keeps pointing there. A `path` that is no regular file
    (`unwritable_kind`: a device such as /dev/null, a fifo, a folder) raises OSError untouched: a
    rename would replace it."""
    kind = unwritable_kind(path)
    if kind is not None:
        raise OSError(f"{path!r} is {kind}: only a regular file (or a new name) can be replaced "
                      "atomically")
    path = destination(path)
    folder = os.path.dirname(os.path.abspath(path))
    mode = creation_mode(path)
    fd, tmp = tempfile.mkstemp(prefix="." + os.path.basename(path) + ".", suffix=".part", dir=folder)
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


def write_image(image, path: str, pixel_format: str = "rgb", aovs: dict | None = None, plain: bool = False) -> None:
    """Write `image` atomically: EXR as linear float32, PNG as sRGB 8 bit, clamped.

    Args:
        image: H x W x C linear pixels.
        path: the destination; its extension chooses the format.
        pixel_format: the film's pixel format (see `encode`).
        aovs: the error AOVs as extra channels (EXR only), or None.
        plain: encode with `encode_plain` (no Mitsuba: a kernel may be running).

    Raises:
        OSError: the file cannot be written. ValueError: AOVs for a format other than EXR.
    """
    ext = os.path.splitext(path)[1].lower()
    if plain:
        write_bytes_atomically(encode_plain(image, ext, pixel_format, aovs), path)
        return
    if aovs is not None:
        if ext != ".exr":
            raise ValueError(f"error AOVs are written to .exr files only, not {ext!r}")
        write_bytes_atomically(encode_with_aovs(image, aovs, pixel_format), path)
        return
    write_bytes_atomically(encode(image, ext, pixel_format), path)


def save_safely(image, path: str, pixel_format: str = "rgb", aovs: dict | None = None, plain: bool = False) -> str:
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
    """`path` can be replaced by renaming a new file over it (images.write_bytes_atomically): a
    regular file or a new name in an existing, writable folder; a symbolic link counts as its
    target, which is where the file goes (the link stays). Devices (/dev/null included: the rename
    would replace the device node, so it is refused rather than written to), fifos, sockets and
    folders are refused untouched."""
    kind = unwritable_kind(path)
    if kind is not None:
        via = f" (a link to {os.path.realpath(path)!r})" if os.path.islink(path) else ""
        raise UsageError(f"cannot write {path!r}: it is {kind}{via}; expected a regular file or a "
                         "new name")
    target = destination(path)
    folder = os.path.dirname(os.path.abspath(target))
    if not os.path.isdir(folder):
        raise UsageError(f"cannot write {path!r}: folder {folder!r} does not exist")
    if not os.access(folder, os.W_OK) or (os.path.exists(target) and not os.access(target, os.W_OK)):
        raise UsageError(f"cannot write {path!r}: permission denied")

__all__ = [
    "check_target",
    "IMAGE_TYPES",
    "PIXEL_FORMATS",
    "AOV_CHANNELS",
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
