"""Host arrays handed to kernels (host_arrays.py): 64-byte aligned copies, so that a kernel has one
code whatever numpy's allocation. The reason, checked against Dr.Jit itself: a kernel that reads a
numpy array mapped at a 64-byte boundary and the same kernel reading one that is not get two
different hashes in Dr.Jit's kernel history; through `aligned` both get the first one."""
import numpy as np

from styletrace.gate import dr, mi
from styletrace.host_arrays import ALIGNMENT, aligned

N = 4096


def at(offset_bytes: int) -> np.ndarray:
    """N float32 values whose data starts `offset_bytes` past a 64-byte boundary."""
    raw = np.empty(N * 4 + 2 * ALIGNMENT, dtype=np.uint8)
    start = (-raw.ctypes.data) % ALIGNMENT + offset_bytes
    out = raw[start:start + N * 4].view(np.float32)
    out[:] = np.arange(N, dtype=np.float32)
    return out


def kernel_hash(x: np.ndarray) -> str:
    dr.kernel_history()  # reading it empties it
    y = mi.Float(x) * 3.0 + 1.0
    dr.eval(y)
    launches = [k for k in dr.kernel_history() if "hash" in k]
    assert len(launches) == 1
    assert np.allclose(np.array(y), np.asarray(x) * 3.0 + 1.0)
    return launches[0]["hash"]


def test_aligned_copies_start_on_a_64_byte_boundary():
    for dtype in (np.float32, np.uint32, np.int32):
        for n in (1, 3, 1000, 40000):
            a = np.arange(n).reshape(-1, 1) % 7
            out = aligned(a, dtype)
            assert out.ctypes.data % ALIGNMENT == 0 and out.flags.c_contiguous
            assert out.dtype == dtype and out.shape == a.shape and np.array_equal(out, a)


def test_a_kernel_has_one_code_whatever_the_arrays_alignment():
    dr.set_flag(dr.JitFlag.KernelHistory, True)
    try:
        on_boundary, off_boundary = kernel_hash(at(0)), kernel_hash(at(4))
        assert on_boundary != off_boundary  # Dr.Jit's own behaviour: the reason for `aligned`
        assert kernel_hash(aligned(at(4))) == kernel_hash(aligned(at(0))) == on_boundary
    finally:
        dr.set_flag(dr.JitFlag.KernelHistory, False)
