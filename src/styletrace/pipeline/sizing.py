"""Camera samples per pass for the backend and the device the render runs on.

    lanes, note = lanes_per_pass("llvm_ad_rgb")   # 2^20 (pass_loop.LANES_PER_PASS)
    lanes, note = lanes_per_pass("cuda_ad_rgb")   # from the GPU's memory; note: cut by free memory

CUDA: `CUDA_MEMORY_SHARE` of the device's total memory at `CUDA_LANE_BYTES` per lane, a power of
two, halved (with a note) while it does not fit into the free memory. The split depends on the
backend and the device model, never on timing; `--pass-spp` fixes it. Rationale:
docs/design/pass_sizes.md.
"""
from __future__ import annotations

import ctypes
from typing import Callable, Optional

from styletrace.pipeline import passes as pass_loop

CUDA_LANE_BYTES = 1024
#: The share of the GPU's total memory a pass may use (the scene, the film and Dr.Jit's caches need
#: the rest).
CUDA_MEMORY_SHARE = 0.5
#: Dr.Jit indexes lanes with 32-bit integers; stay well below.
CUDA_LANES_MAX = 1 << 30

MemoryQuery = Callable[[], Optional[tuple]]  # () -> (free bytes, total bytes) or None


def cuda_memory(ordinal: int = 0) -> tuple[int, int] | None:
    """(free, total) bytes of a CUDA device through the driver API (libcuda).

    Dr.Jit uses the device's primary context, so retaining it here creates nothing new.

    Args:
        ordinal: the device's index.

    Returns:
        (free, total) in bytes; (total, total) where the free memory cannot be read; None where the
        driver or the device is unavailable.
    """
    try:
        cuda = ctypes.CDLL("libcuda.so.1")
    except OSError:
        return None
    dev, ctx = ctypes.c_int(), ctypes.c_void_p()
    free, total = ctypes.c_size_t(), ctypes.c_size_t()
    if cuda.cuInit(0) or cuda.cuDeviceGet(ctypes.byref(dev), ordinal) \
            or cuda.cuDeviceTotalMem_v2(ctypes.byref(total), dev):
        return None
    if cuda.cuDevicePrimaryCtxRetain(ctypes.byref(ctx), dev):
        return total.value, total.value
    try:
        if cuda.cuCtxPushCurrent_v2(ctx):
            return total.value, total.value
        try:
            if cuda.cuMemGetInfo_v2(ctypes.byref(free), ctypes.byref(ctypes.c_size_t())):
                return total.value, total.value
        finally:
            cuda.cuCtxPopCurrent_v2(ctypes.byref(ctypes.c_void_p()))
    finally:
        cuda.cuDevicePrimaryCtxRelease_v2(dev)
    return free.value, total.value


def _pow2_floor(x: int) -> int:
    return 1 << (max(int(x), 1).bit_length() - 1)


def lanes_per_pass(variant: str, query: MemoryQuery = cuda_memory) -> tuple[int, str | None]:
    """Camera samples per pass for a backend.

    Args:
        variant: the Mitsuba variant, e.g. "llvm_ad_rgb" or "cuda_ad_rgb".
        query: returns the CUDA device's (free, total) bytes, or None where it cannot tell.

    Returns:
        (lanes, note): the pass size, and a note for the user when free memory lowered it,
        else None.
    """
    if not variant.startswith("cuda"):
        return pass_loop.LANES_PER_PASS, None
    memory = query()
    if memory is None:  # no driver API to ask: the CPU's size is safe everywhere
        return pass_loop.LANES_PER_PASS, None
    free, total = memory
    lanes = min(
        CUDA_LANES_MAX,
        max(pass_loop.LANES_PER_PASS, _pow2_floor(total * CUDA_MEMORY_SHARE // CUDA_LANE_BYTES)),
    )
    default = lanes
    while lanes > pass_loop.LANES_PER_PASS and lanes * CUDA_LANE_BYTES > free:
        lanes //= 2
    note = None
    if lanes != default:
        note = (
            f"only {free / 2**30:.1f} GiB of GPU memory free: passes of {lanes} samples instead of "
            f"{default}, so the image differs from this device's default split (--pass-spp fixes "
            "it)"
        )
    return lanes, note


__all__ = [
    "lanes_per_pass",
    "cuda_memory",
    "CUDA_LANE_BYTES",
    "CUDA_MEMORY_SHARE",
    "CUDA_LANES_MAX",
]
