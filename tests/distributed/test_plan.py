"""The (tile, pass) units are api.passes' launches; their merge is order-independent, bit for
bit."""
import numpy as np

from styletrace.frontends import api
from styletrace.pipeline.passes import PassSplit
from styletrace.pipeline.ray_plan import Merge, Plan, plan_units


def test_units_follow_api_passes_launch_order_seeds_and_counts():
    layout, units = plan_units(Plan(2100, 1024, 7, 9, PassSplit(pass_spp=3)))
    assert len(layout) == 3 and [u.spp for u in units[::3]] == [3, 3, 1]
    assert [u.index for u in units] == list(range(9))
    assert [(u.tile, u.round) for u in units[:4]] == [(0, 0), (1, 0), (2, 0), (0, 1)]
    assert all(u.seed == api.pass_seed(9, u.index) for u in units)


def test_merge_in_any_arrival_order_is_bit_identical():
    layout, units = plan_units(Plan(30, 20, 40, 0, PassSplit(pass_spp=1)))
    rng = np.random.default_rng(3)
    tiles = [
        (rng.random((20, 30, 3)) * 10.0 ** rng.integers(-3, 4)).astype(np.float32) for _ in units
    ]
    forward, backward = Merge(30, 20, 40, layout), Merge(30, 20, 40, layout)
    for u, t in zip(units, tiles):
        forward.add(u, t)
    for u, t in reversed(list(zip(units, tiles))):
        backward.add(u, t)
    assert np.array_equal(forward.total, backward.total)
    naive = np.zeros((20, 30, 3), np.float32)
    for t in reversed(tiles):
        naive += t
    # float32 summation order matters: the test can fail
    assert not np.array_equal(naive, forward.total)
    assert forward.progress().spp_done == 40
