"""reuse=pixels with stylize=first_n_hits and reuse_deep=world (kernel/reuse_world.py,
kernel/world_grid.py): the second-level vertices pool their world-space neighbours' children too,
then the first hits pool theirs.

Truth from outside the pooling code: the analytic glowing shell, Mitsuba's `path` on the Cornell
box, and the pools a render used checked against the stored positions with numpy.
"""
import numpy as np
import pytest

import styletrace
from styletrace.errors import SettingsError
from styletrace.frontends import api
from styletrace.gate import mi
from styletrace.kernel import reuse

from .test_reuse import Z, seed_means
from .test_reuse_depth2 import DEPTH2, shell_scene

WORLD = dict(reuse="pixels", reuse_deep="world", **DEPTH2)


@pytest.fixture(scope="module")
def shell():
    return mi.load_dict(shell_scene())


@pytest.mark.parametrize("weights", ["balance", "pairwise"])
def test_world_identity_inside_a_glowing_shell_is_exact(shell, weights):
    integ = api.make_integrator("identity", inner=2, reuse_k=12, reuse_mis=weights, **WORLD)
    means = seed_means(shell, integ, 6, 8)
    z = (means.mean() - 2.0) / (means.std(ddof=1) / np.sqrt(len(means)))
    assert abs(z) < Z, f"image mean {means.mean()} vs exact 2: z = {z}"


def test_world_own_density_weights_darken_the_shell(shell):
    integ = api.make_integrator("identity", inner=2, reuse_k=12, **WORLD)
    means = seed_means(shell, integ, 6, 8, weights="own")
    z = (means.mean() - 2.0) / (means.std(ddof=1) / np.sqrt(len(means)))
    assert z < -Z, f"own pdf: image mean {means.mean()}, z = {z} (expected darker than 2)"


def test_world_identity_on_the_cornell_box_matches_path():
    """As test_identity_on_the_cornell_box_matches_path, with the second level pooled over
    world-space neighbours (a blur of radius h there: its effect on the image mean is below the
    standard error)."""
    scene = api.load_scene("cornell-box", 32, 32)
    path = mi.load_dict({"type": "path"})
    refs = np.array(
        [
            np.asarray(mi.render(scene, integrator=path, spp=256, seed=s), dtype=np.float64)[
                ..., :3
            ].mean()
            for s in range(6)
        ]
    )
    integ = api.make_integrator("identity", inner="1,1", reuse_k=8, reuse_mis="pairwise", **WORLD)
    means = seed_means(scene, integ, 6, 32)
    se = np.hypot(means.std(ddof=1), refs.std(ddof=1)) / np.sqrt(len(means))
    z = (means.mean() - refs.mean()) / se
    assert abs(z) < Z, f"reuse {means.mean()} vs path {refs.mean()}: z = {z}"


def test_world_pools_on_the_cornell_box_hold_neighbours_within_h_only():
    """The pools a render used, rebuilt from the stored grid and checked against the stored
    positions: every accepted neighbour lies within h, and the pools are not trivially empty."""
    scene = api.load_scene("cornell-box", 16, 16)
    integ = api.make_integrator("identity", inner="2,1", reuse_k=8, reuse_k2=12, **WORLD)
    keep = {}
    reuse.render_reuse(integ, scene, scene.sensors()[0], 5, 4, keep=keep)
    P, mask, h = keep["world_p"], keep["world_mask"], keep["world_h"]
    order, first, count, offset = (
        keep[k].astype(np.int64)
        for k in ("world_order", "world_first", "world_count", "world_offset")
    )
    sizes = []
    for i in np.flatnonzero(keep["world_pool"]):
        members = [i] + [
            order[first[i] + (offset[i] + q - 1) % count[i]]
            for q in range(1, keep["world_k"] + 1)
            if int(mask[i]) >> q & 1
        ]
        assert keep["world_pool"][members].all()
        d = np.linalg.norm(P[:, members] - P[:, [i]], axis=0)
        assert np.all(d <= h * (1 + 1e-5)), f"vertex {i}: neighbours at {d.max()} > h = {h}"
        sizes.append(len(members))
    assert np.mean(sizes) > 3


def test_world_same_seed_bit_identical():
    kw = dict(style="saturation", width=16, height=16, spp=2, seed=7, inner="2,1", **WORLD)
    a, b = styletrace.render("cornell-box", **kw), styletrace.render("cornell-box", **kw)
    assert np.array_equal(a, b)
    assert not np.array_equal(a, styletrace.render("cornell-box", **{**kw, "seed": 8}))


WORLD_BAD = [
    (dict(reuse="pixels", reuse_deep="world"), "bad value 'world' for 'reuse_deep'"),
    (dict(reuse="pixels", reuse_deep="world", stylize="first_n_hits", stylize_depth=3),
     "bad value 'world' for 'reuse_deep'"),
    (dict(reuse_deep="world", **DEPTH2), "bad value 'world' for 'reuse_deep'"),
    (dict(reuse="pixels", reuse_deep="hash", **DEPTH2), "bad value 'hash' for 'reuse_deep'"),
    (dict(reuse_h=1e-5, **WORLD), "bad value 1e-05 for 'reuse_h'"),
    (dict(reuse_h=2, **WORLD), "bad value 2 for 'reuse_h'"),
    (dict(reuse_k2=64, **WORLD), "bad value 64 for 'reuse_k2'"),
    (dict(WORLD, inner_samples="2:8,1"), "bad value '2:8' for 'inner_samples'"),
    (dict(WORLD, inner_samples="2,1:4"), "bad value '1:4' for 'inner_samples'"),
]


@pytest.mark.parametrize("values,message", WORLD_BAD, ids=[m for _, m in WORLD_BAD])
def test_world_bad_settings_one_line(values, message):
    with pytest.raises(SettingsError) as err:
        api.make_integrator(**values)
    assert message in str(err.value) and "\n" not in str(err.value)
