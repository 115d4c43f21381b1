"""The pass split (pipeline/passes.py): even rounds, and rounds that grow from the first pass's
camera samples to what the lanes allow (F12 with the `owen_sobol` sampler), which render the same
image to float rounding."""
import numpy as np

from styletrace.frontends import api
from styletrace.pipeline.passes import PassSplit, pass_count


def test_even_rounds_end_with_what_is_left():
    _, rounds = PassSplit(1 << 20, 4).rounds(128, 128, 18)
    assert rounds == [4, 4, 4, 4, 2]


def test_growing_rounds_double_up_to_the_lanes():
    # 128 x 128 with 2^20 lanes: at most 64 camera samples per pixel a pass
    _, rounds = PassSplit(1 << 20, 1, grow=True).rounds(128, 128, 1024)
    assert rounds[:7] == [1, 2, 4, 8, 16, 32, 64] and set(rounds[7:-1]) == {64}
    assert sum(rounds) == 1024 and len(rounds) == 7 + (1024 - 127) // 64 + 1
    _, rounds = PassSplit(1 << 20, 4, grow=True).rounds(128, 128, 16)
    assert rounds == [4, 8, 4]
    _, rounds = PassSplit(1 << 20, 1, grow=True).rounds(128, 128, 64)
    assert rounds == [1, 2, 4, 8, 16, 32, 1]


def test_pass_count_counts_the_rounds():
    scene = api.load_scene("cornell-box", 16, 16)
    assert pass_count(scene, 64, 1 << 20, 1) == 64
    assert pass_count(scene, 64, 1 << 20, 1, grow=True) == 7


def test_growing_passes_render_the_even_passes_image():
    """With `owen_sobol` the passes continue one sequence: the split changes only the rounding."""
    scene = api.load_scene("cornell-box", 16, 16)
    integ = api.make_integrator("identity", inner=1)
    even = list(api.passes(scene, integ, 24, seed=2, pass_spp=1))[-1].image
    from styletrace.pipeline.passes import Shot, run_passes
    grown = list(run_passes(Shot(scene, integ, 24, 2), PassSplit(1 << 20, 1, grow=True)))
    assert [p.pass_spp for p in grown] == [1, 2, 4, 8, 9]
    np.testing.assert_allclose(grown[-1].image, even, rtol=1e-5, atol=1e-6)
