"""Host (numpy) arrays handed to Dr.Jit kernels, 64-byte aligned.

    xs = mi.Float(aligned(x))       # not mi.Float(x)

On the LLVM backend Dr.Jit maps a contiguous numpy array's memory into a kernel without copying it,
and the code it generates to load it depends on the pointer: `align 64` where it is 64-byte
aligned, `align 1` where not. numpy's allocator returns either, by chance, so one kernel had two
codes, two hashes in Dr.Jit's kernel cache, and was compiled again whenever the other came up (the
scene pilot's path kernel, about 4000 operations: seconds on a cold cache, after a viewport's seed
change; tests/blender/test_viewport_seed.py). An array made here is always aligned, so its kernels
have one code.
"""
from __future__ import annotations

import numpy as np

#: the alignment Dr.Jit's own allocations have, and its kernels assume where they can
ALIGNMENT = 64


def aligned(a, dtype=np.float32) -> np.ndarray:
    """A C-contiguous copy of `a` whose data starts on an ALIGNMENT-byte boundary.

    Args:
        a: anything numpy reads as an array. dtype: the copy's element type.

    Returns:
        The copy (it keeps its own buffer alive), `a`'s shape.
    """
    a = np.asarray(a, dtype=dtype)
    raw = np.empty(a.nbytes + ALIGNMENT, dtype=np.uint8)
    start = (-raw.ctypes.data) % ALIGNMENT
    out = raw[start:start + a.nbytes].view(dtype).reshape(a.shape)
    out[...] = a
    return out


__all__ = ["aligned", "ALIGNMENT"]
