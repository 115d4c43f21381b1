"""reuse=pixels with stylize=first_n_hits (kernel/reuse/): the first hits pool their children, each
child's value being the stylized value of the level-1 vertex it reaches (computed by the ordinary
tree, deeper first).

Truth from outside the pooling code: an analytic glowing shell (radiance Le / (1 - albedo)
everywhere, also in a mirror ball inside it), Mitsuba's `path` on the Cornell box and on a room
scene whose ball turns its normals fast, and the tree sampler at a large n on the same camera rays.
Pooled pixels are correlated, so standard errors come from independent seeds (one image mean each).
"""
import numpy as np
import pytest

import styletrace
from styletrace.errors import SettingsError
from styletrace.frontends import api
from styletrace.gate import mi
from styletrace.kernel import reuse

from .test_reuse import Z, film, room_scene, seed_means

T = mi.ScalarTransform4f
DEPTH2 = dict(stylize="first_n_hits", stylize_depth=2)


def shell_scene(res=16):
    """The camera inside a diffuse sphere (albedo 0.5) that emits radiance 1 inwards, off its
    centre, and a perfect mirror ball in view: the radiance is 1 / (1 - 0.5) = 2 along every ray,
    mirror included. The normals and camera distances change from pixel to pixel, and the
    mirror's lanes cannot pool."""
    return {"type": "scene",
            "sensor": {"type": "perspective", "fov": 60, "film": film(res),
                       "to_world": T().look_at(origin=[0, 0, 0.3], target=[0, 0, -1], up=[0, 1, 0]),
                       "sampler": {"type": "independent", "sample_count": 4}},
            "shell": {"type": "sphere", "radius": 1.0, "flip_normals": True,
                      "bsdf": {"type": "diffuse", "reflectance": {"type": "rgb", "value": 0.5}},
                      "emitter": {"type": "area", "radiance": {"type": "rgb", "value": 1.0}}},
            "mirror": {"type": "sphere", "radius": 0.15, "center": [0.25, 0.1, -0.5],
                       "bsdf": {"type": "conductor", "material": "none"}}}


@pytest.fixture(scope="module")
def shell():
    return mi.load_dict(shell_scene())


@pytest.mark.parametrize("depth,weights", [(2, "balance"), (2, "pairwise"), (3, "pairwise")])
def test_identity_inside_a_glowing_shell_is_exact(shell, depth, weights):
    """Depth 3 runs the same recursion one level further (the level-1 vertices are stylized by
    the tree)."""
    integ = api.make_integrator(
        "identity",
        inner=2,
        stylize="first_n_hits",
        stylize_depth=depth,
        reuse="pixels",
        reuse_k=12,
        reuse_mis=weights,
    )
    means = seed_means(shell, integ, 6, 8)
    z = (means.mean() - 2.0) / (means.std(ddof=1) / np.sqrt(len(means)))
    assert abs(z) < Z, f"image mean {means.mean()} vs exact 2: z = {z}"


def test_own_density_weights_darken_the_shell(shell):
    """The negative control of the test above: dividing each pooled sample by its own density
    misses the directions a neighbour with another normal cannot sample (measured: 0.3 % dark, z
    about -6)."""
    integ = api.make_integrator("identity", inner=2, reuse="pixels", reuse_k=12, **DEPTH2)
    means = seed_means(shell, integ, 6, 8, weights="own")
    z = (means.mean() - 2.0) / (means.std(ddof=1) / np.sqrt(len(means)))
    assert z < -Z, f"own pdf: image mean {means.mean()}, z = {z} (expected darker than 2)"


def test_identity_on_the_cornell_box_matches_path():
    """The image mean against Mitsuba's `path`, within 4 standard errors of the two. The window
    blur moves light between neighbouring pixels (docs/reuse.md), which changes the image mean by
    about 0.1 % at the first hit, well below the standard error here (about 0.4 %)."""
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
    integ = api.make_integrator("identity", inner="1,1", reuse="pixels", reuse_k=8, **DEPTH2)
    means = seed_means(scene, integ, 6, 64)
    se = np.hypot(means.std(ddof=1), refs.std(ddof=1)) / np.sqrt(len(means))
    z = (means.mean() - refs.mean()) / se
    assert abs(z) < Z, f"reuse {means.mean()} vs path {refs.mean()}: z = {z}"


def test_mixture_weights_unbiased_on_a_turning_ball_own_weights_not(monkeypatch):
    """The room scene of test_reuse at depth 2, acceptance wide open: the ball's pools take
    neighbours of any normal. Balance weights stay within 4 standard errors of `path`;
    own-density weights are rejected."""
    scene = mi.load_dict(room_scene())
    res = 16
    yy, xx = np.mgrid[0:res, 0:res]
    c = (res - 1) / 2
    rpix = np.tan(np.arcsin(0.5 / 3)) / np.tan(np.radians(15)) * res / 2
    mask = (xx - c) ** 2 + (yy - c) ** 2 < (0.85 * rpix) ** 2
    path = mi.load_dict({"type": "path"})
    refs = np.array(
        [
            np.asarray(mi.render(scene, integrator=path, spp=1024, seed=s), dtype=np.float64)[
                ..., :3
            ][mask].mean()
            for s in range(4)
        ]
    )
    monkeypatch.setattr(reuse.pool, "NORMAL_MIN", -1.0)
    monkeypatch.setattr(reuse.pool, "DEPTH_TOL", 10.0)
    integ = api.make_integrator(
        "identity", inner="1,1", reuse="pixels", reuse_radius=3, reuse_k=48, **DEPTH2
    )

    def z(weights):
        means = seed_means(scene, integ, 6, 64, mask, weights=weights)
        se = np.hypot(
            means.std(ddof=1) / np.sqrt(len(means)), refs.std(ddof=1) / np.sqrt(len(refs))
        )
        return (means.mean() - refs.mean()) / se

    z_mixture = z("balance")
    assert abs(z_mixture) < Z, f"balance weights: z = {z_mixture}"
    z_own = z("own")
    assert z_own < -Z, f"own pdf: z = {z_own} (expected darker than path)"


def test_saturation_with_reuse_beats_the_tree_with_twice_the_children():
    """Same seed, so the same camera rays: the error is the inner estimate's alone. Reference:
    the tree at 64,8 children. Pooling K = 8 neighbours' 4 children per first hit must beat the
    tree at 8,4."""
    kw = dict(style="saturation", width=32, height=32, spp=1, seed=3, **DEPTH2)
    ref = styletrace.render("cornell-box", inner="64,8", **kw)
    mse = {
        n: ((styletrace.render("cornell-box", inner=f"{n},4", **kw) - ref) ** 2).mean()
        for n in (4, 8)
    }
    pooled = (
        (styletrace.render("cornell-box", inner="4,4", reuse="pixels", reuse_k=8, **kw) - ref) ** 2
    ).mean()
    assert mse[8] < mse[4]
    assert pooled < mse[8], f"MSE with reuse {pooled:.3e}, tree 8,4 {mse[8]:.3e}, 4,4 {mse[4]:.3e}"


def test_same_seed_bit_identical():
    kw = dict(
        style="saturation",
        width=16,
        height=16,
        spp=2,
        seed=7,
        inner="2,2",
        reuse="pixels",
        **DEPTH2,
    )
    a, b = styletrace.render("cornell-box", **kw), styletrace.render("cornell-box", **kw)
    assert np.array_equal(a, b)
    assert not np.array_equal(a, styletrace.render("cornell-box", **{**kw, "seed": 8}))


BAD = [
    (
        dict(reuse="pixels", stylize="first_object_hit", stylize_depth=2),
        "reuse=pixels pools samples at the first hit",
    ),
    (dict(reuse="pixels", style="gamma", estimator="series", **DEPTH2), "supports 'direct' only"),
    (dict(reuse="pixels", style="acp", **DEPTH2), "cannot be used with reuse=pixels"),
]


@pytest.mark.parametrize("values,message", BAD, ids=[m for _, m in BAD])
def test_bad_settings_one_line(values, message):
    with pytest.raises(SettingsError) as err:
        api.make_integrator(**values)
    assert message in str(err.value) and "\n" not in str(err.value)



def test_an_adaptive_first_level_count_refines_the_first_hits():
    """n0:n_max at the first level with reuse_deep=tree: the first hits' refinement round
    (test_reuse_refine) works as at first_hit, its extra children valued by the tree below: the
    lanes the rule flags store n_max children, the others n0, and the image is finite and differs
    from the fixed count n0's."""
    from .test_reuse_refine import refined
    scene = api.load_scene("cornell-box", 24, 24)
    img, keep = refined(scene, inner="2:8,2", spp=1, thresholds=[0.05, 0.2], levels=[0.1, 0.5, 0.9],
                        stylize="first_n_hits", stylize_depth=2)
    flag, hit = keep["flag"], keep["target"] >= 0
    assert 0 < flag.sum() < hit.sum()
    assert (keep["stored"][flag] == 8).all() and (keep["stored"][~flag & hit] == 2).all()
    fixed, _ = refined(scene, inner="2,2", spp=1, thresholds=[0.05, 0.2], levels=[0.1, 0.5, 0.9],
                       stylize="first_n_hits", stylize_depth=2)
    assert np.isfinite(img).all() and not np.array_equal(img, fixed)
