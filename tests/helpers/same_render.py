"""Two renders of one job compared as Mitsuba's film allows.

Mitsuba's film adds a pixel's camera samples with atomic adds. On the LLVM backend a pixel whose
samples fall in two of Dr.Jit's thread blocks (spp not a power of two) is summed in whichever
order the threads finish, so the same job can differ in the last bits of that pixel from run to
run. A float32 sum of k terms taken in two orders differs by at most 2(k - 1) eps times the sum
of their magnitudes, so the mean of k samples by 2(k - 1) eps times their mean magnitude: `scale`
bounds that magnitude (default: the larger of 1 and the image's largest value, which holds for
the non-negative samples of the styles these tests render)."""
import numpy as np

EPS32 = float(np.finfo(np.float32).eps)


def assert_same_render(got, want, spp: int, scale: float | None = None):
    got, want = np.asarray(got), np.asarray(want)
    assert got.shape == want.shape, (got.shape, want.shape)
    scale = max(1.0, float(np.abs(want).max())) if scale is None else scale
    bound = 2 * max(spp - 1, 0) * EPS32 * scale
    np.testing.assert_allclose(got, want, rtol=0, atol=bound)
