"""The lanes' sequences (kernel/sequence_sampler.py): children of one camera sample independent,
each child's numbers stratified across the camera samples of its pixel, and new dimensions on
every iteration of a symbolic loop."""
import numpy as np

from styletrace.gate import dr, mi
from styletrace.kernel.sequence_sampler import SequenceSampler, pixel_key

PIXELS, SPP = 1024, 16
N = PIXELS * SPP


def lanes(cls=SequenceSampler) -> SequenceSampler:
    """PIXELS pixels of SPP camera samples each, pixel-major, as Mitsuba's render loop lays them."""
    lane = dr.arange(mi.UInt32, N)
    pixel = lane // SPP
    return cls(pixel_key(7, 0, pixel), lane - pixel * SPP, mi.UInt32(3))


def children_product(smp: SequenceSampler, children: int = 2) -> np.ndarray:
    """The product of one number of each of `children` children, drawn in a symbolic loop as the
    estimators draw them (`StylizedIntegrator.estimate`)."""
    def body(k, prod, s):
        child = s.split()
        return k + 1, prod * child.next_1d(), s

    _, prod, _ = dr.while_loop((mi.UInt32(0), mi.Float(1.0), smp), lambda k, p, s: k < children,
                               body)
    return np.asarray(prod, np.float64)


class SharedStreams(SequenceSampler):
    """A broken split: every child continues the parent's stream from the same dimension, so the
    children of one camera sample share their numbers."""
    def split(self):
        return SequenceSampler(self.key, self.index, self.dim, self.spawned)


def test_children_of_one_camera_sample_are_independent():
    """E[u1 u2] = 1/4 for independent uniforms (1/3 if shared), within 5 standard errors (the
    independent draws' standard deviation, sqrt(1/9 - 1/16), over sqrt(N): an upper bound, the
    lanes of one pixel being stratified)."""
    bound = 5 * np.sqrt(1 / 9 - 1 / 16) / np.sqrt(N)
    assert abs(children_product(lanes()).mean() - 0.25) < bound
    assert abs(children_product(lanes(), 3).mean() - 0.125) < 5 * np.sqrt(1 / 27) / np.sqrt(N)


def test_the_check_fails_when_children_share_their_numbers():
    bound = 5 * np.sqrt(1 / 9 - 1 / 16) / np.sqrt(N)
    assert abs(children_product(lanes(SharedStreams)).mean() - 0.25) > bound


def test_grandchildren_are_independent_of_their_uncles():
    """A child's own child (first_n_hits' next level) and the next child of the root."""
    smp = lanes()
    first = smp.split()
    grandchild = first.split()
    second = smp.split()
    a = np.asarray(grandchild.next_1d(), np.float64)
    b = np.asarray(second.next_1d(), np.float64)
    assert abs(np.corrcoef(a, b)[0, 1]) < 5 / np.sqrt(N)


def test_each_child_is_stratified_over_its_pixels_camera_samples():
    """Child k's first number over the 16 camera samples of a pixel: one in each sixteenth."""
    smp = lanes()
    for _ in range(3):
        u = np.asarray(smp.split().next_1d()).reshape(PIXELS, SPP)
        bins = np.sort((u * SPP).astype(int), axis=1)
        assert (bins == np.arange(SPP)).all()


def test_a_symbolic_loop_draws_new_dimensions_each_iteration():
    """Four iterations of a symbolic loop (the path loop's bounces) draw four different numbers,
    and the dimension counter comes out advanced."""
    def body(k, first, s, same):
        u = s.next_1d()
        same |= (k > 0) & (u == first)
        return k + 1, dr.select(k == 0, u, first), s, same

    state = (mi.UInt32(0), mi.Float(0.0), lanes(), mi.Bool(False))
    _, _, out, same = dr.while_loop(state, lambda k, f, s, m: k < 4, body)
    assert not np.asarray(same).any()
    assert (np.asarray(out.dim) == 3 + 4).all()


def test_pixels_have_their_own_sequences():
    """Two pixels' first numbers are unrelated: the keys differ, so do the shuffles."""
    smp = lanes()
    u = np.asarray(smp.next_1d()).reshape(PIXELS, SPP)
    assert abs(np.corrcoef(u[0::2].ravel(), u[1::2].ravel())[0, 1]) < 5 / np.sqrt(N / 2)
