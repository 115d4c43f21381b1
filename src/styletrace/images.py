"""Writing rendered images: EXR as linear float32, PNG as sRGB 8-bit.

`save_safely` never loses a finished render: if the requested path cannot be written, the image goes
to a temporary EXR instead and the caller is told where.
"""
from __future__ import annotations

import os
import sys
import tempfile

IMAGE_TYPES = (".exr", ".png")


def write_image(image, path: str) -> None:
    """EXR: linear float32. PNG: sRGB-encoded 8 bit (values clipped to [0, 1] only here)."""
    import mitsuba as mi
    import numpy as np

    from .jit import backend
    backend()
    bmp = mi.Bitmap(np.ascontiguousarray(image, dtype=np.float32), pixel_format=mi.Bitmap.PixelFormat.RGB)
    if path.lower().endswith(".png"):
        bmp = bmp.convert(pixel_format=mi.Bitmap.PixelFormat.RGB, component_format=mi.Struct.Type.UInt8,
                          srgb_gamma=True)
    bmp.write(path)


def save_safely(image, path: str) -> str:
    """Write `image`; if that fails, keep it in a temporary EXR instead of losing it. Returns where it went."""
    try:
        write_image(image, path)
        return path
    except Exception as exc:  # the render must survive an I/O failure
        fd, fallback = tempfile.mkstemp(prefix="styletrace-", suffix=".exr")
        os.close(fd)
        write_image(image, fallback)
        print(f"styletrace: could not write {path!r} ({exc}); saved the render to {fallback}", file=sys.stderr)
        return fallback


__all__ = ["IMAGE_TYPES", "write_image", "save_safely"]
