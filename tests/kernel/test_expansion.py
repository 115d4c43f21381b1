"""The expansion pass (`expansion_pass`, kernel/expansion.py): the series estimators' b from a
separate pass.

Unbiased on the furnace (first-hit radiance I = rho * E exactly, one independent estimate per sphere
pixel at spp 1); the render's first level uses the pass's b (per lane, not a pilot), computed from
the pixel's and its window's moments with the lane's emission added back; the pass has its own seed
stream; the same seed gives the same image bit for bit; tiles get a pass each; bad values are
refused with one line.
"""
import numpy as np
import pytest
from helpers import furnace
from helpers.furnace import I, z_score

from styletrace import wild
from styletrace.config import estimator_registry as estimation
from styletrace.config import settings as S
from styletrace.errors import SettingsError
from styletrace.estimators.base import Context
from styletrace.frontends import api
from styletrace.gate import mi
from styletrace.styles import create
from styletrace.styles.base import Vertex

RES = 48
Z = 4.0


# g(x, s): s the exposure the render resolved (auto; the pass's moments are of unexposed children,
# scaled by it)
@pytest.mark.parametrize("style,g", [
    ("gamma", lambda x, s: (s * x) ** (1 / 2.2)),          # power series, scaled terms
    # reciprocal series of the shifted sample 1 + s I
    ("reinhard", lambda x, s: s * x / (1 + s * x)),
    ("exp_tone", lambda x, s: 1 - np.exp(-s * x)),         # exp series, unscaled
])
def test_series_with_the_pass_is_unbiased_on_the_furnace(scene, mask, style, g):
    vals = furnace.draws(scene, mask, style, 4, 6, 100, estimator="series", expansion_pass=16)
    s = furnace.resolved(scene, style, estimator="series", expansion_pass=16).exposure
    z = z_score(vals, g(I, s))
    assert np.all(np.abs(z) < Z), (style, z, vals.mean(0), g(I))


def test_the_first_level_expands_about_the_pass_b_not_a_pilot():
    """With the pass's moments the level-0 estimator's b is 2 x the larger b* of the pixel's own
    and its window's moments, the lane's emission e added back (b* of e + R), floored at gamma's
    0.02; no pilot children. Deeper levels (and no moments) keep the in-lane pilot of n children."""
    style = create("gamma")
    slot = S.StyleSlot(style, (16,), "series")
    v = Vertex(
        p=mi.Point3f(0),
        n=mi.Vector3f(0, 0, 1),
        wo=mi.Vector3f(0, 0, 1),
        view=mi.Vector3f(0, 0, 1),
        depth=mi.UInt32(0),
    )
    own = (mi.Color3f([0.1, 0.0, 0.5], 0.2, 0.0), mi.Color3f([0.02, 0.0, 2.5], 0.05, 0.0))
    window = (mi.Color3f(0.1, 0.3, 0.0), mi.Color3f(0.05, 0.03, 0.0))
    e = mi.Color3f([0.0, 0.0, 3.0], 0.0, 0.0)
    est = estimation.make_estimator(slot, 0, v, None, ([own, window], e))
    point = est.inner.point
    assert point.pilot is None and point.lane is not None and point.draws == 0
    # lanes x RGB
    b = np.asarray(point.start(Context("drjit", like_t=mi.Color3f))["b"], dtype=np.float64).T
    m1 = np.array([[0.1, 0.2, 0.0], [0.0, 0.2, 0.0], [0.5, 0.2, 0.0]])
    m2 = np.array([[0.02, 0.05, 0.0], [0.0, 0.05, 0.0], [2.5, 0.05, 0.0]])
    w1, w2 = np.array([0.1, 0.3, 0.0]), np.array([0.05, 0.03, 0.0])
    ee = np.array([[0.0, 0.0, 0.0], [0.0, 0.0, 0.0], [3.0, 0.0, 0.0]])

    def bstar(a1, a2):
        n1, n2 = ee + a1, ee * ee + 2 * ee * a1 + a2
        return np.where(n1 > 0, n2 / np.where(n1 > 0, n1, 1), 0)
    want = np.maximum(estimation.PASS_B_SCALE * np.maximum(bstar(m1, m2), bstar(w1, w2)), 0.02)
    assert np.allclose(b, want, rtol=1e-5), (b, want)
    # without moments, and below the first level: the renderer's in-lane pilot of n = 16 children
    for moments, level in ((None, 0), (([own, window], e), 1)):
        assert estimation.make_estimator(slot, level, v, None, moments).inner.point.pilot.n == 16


# The tests below pin gamma's exposure to 1: they read the pass's maps off the integrator they made,
# and an integrator with 'auto' values left is replaced by a resolved copy when it renders
# (scene_defaults.resolve).


def test_the_pass_tames_the_cornell_box():
    """The renderer's series on the Cornell box is wild (test_wild_estimates: values -23.6 to 7.1
    where g lies in [0, 3.8], the light's 18^(1/2.2)); with the pass the same render stays within
    [-1, 4] (measured: -0.25 to 3.78; its 0.29% of slightly negative values still trip the
    warning's threshold of -0.1 x median), and its pass map holds one b* per pixel from its own
    seed."""
    integ = api.make_integrator(
        "gamma", inner=16, estimator="series", expansion_pass=64, exposure=1.0
    )
    img = api.render("cornell-box", integrator=integ, spp=4, width=32, height=32, seed=0)
    frac, lo, hi, _ = wild.measure(img, 0.0, None)
    assert np.all(np.isfinite(img)) and -1.0 < lo and hi < 4.0 and frac < 0.005, (frac, lo, hi)
    (moments,) = integ.expansion.maps.values()
    assert moments.seed == api.expansion_seed(0, 0) and moments.b_star().shape == (32, 32, 3)


def test_the_pass_has_its_own_seed_stream():
    for seed in (0, 1, 12345, 2 ** 32 - 1):
        passes = {api.pass_seed(seed, i) for i in range(200_000)}
        assert all(api.expansion_seed(seed, t) not in passes for t in range(64))
        assert len({api.expansion_seed(seed, t) for t in range(64)}) == 64


def test_the_pass_children_are_not_the_render_children():
    """Rendered with the render's own seed, the pass would draw the render's first children: its
    pixel means would equal the first-pass means of a 1-spp, same-seed moments render. They do
    not (other stream)."""
    scene = api.load_scene("cornell-box", 16, 16)
    integ = api.make_integrator(
        "gamma", inner=16, estimator="series", expansion_pass=16, exposure=1.0
    )
    list(api.passes(scene, integ, 1, seed=3))
    (used,) = integ.expansion.maps.values()
    integ.expansion.clear()
    again = integ.prepare_expansion(scene, api.expansion_seed(3, 0))
    other = integ.prepare_expansion(scene, api.pass_seed(3, 0))
    # the pass is a function of its seed
    assert np.array_equal(used.host[0][0], again.host[0][0])
    # the render's seed draws other children
    assert not np.array_equal(used.host[0][0], other.host[0][0])


def test_same_seed_same_image_bit_for_bit():
    def render(seed):
        integ = api.make_integrator(
            "gamma", inner=8, estimator="series", expansion_pass=16, exposure=1.0
        )
        return api.render("cornell-box", integrator=integ, spp=2, width=16, height=16, seed=seed)
    a, b, c = render(7), render(7), render(8)
    assert np.array_equal(a, b) and not np.array_equal(a, c)


def test_tiles_get_a_pass_each(monkeypatch):
    """A film above LANES_PER_PASS pixels renders as crop windows; each gets its pass (own seed)
    and lookup."""
    from styletrace.pipeline import passes as pass_loop
    monkeypatch.setattr(pass_loop, "LANES_PER_PASS", 256)  # 32 x 16 -> two 32 x 8 tiles
    scene = api.load_scene("cornell-box", 32, 16)
    integ = api.make_integrator(
        "gamma", inner=8, estimator="series", expansion_pass=16, exposure=1.0
    )
    img = list(api.passes(scene, integ, 2, seed=1))[-1].image
    keys = sorted(integ.expansion.maps)
    assert [k[0] for k in keys] == [(0, 0), (0, 8)] and all(k[1] == (32, 8) for k in keys)
    assert sorted(m.seed for m in integ.expansion.maps.values()) == sorted(
        api.expansion_seed(1, t) for t in (0, 1)
    )
    assert np.all(np.isfinite(img)) and img.min() > -1.0


@pytest.mark.parametrize(
    "values,needle",
    [
        (
            {"expansion_pass": -1},
            "bad value -1 for 'expansion_pass': expected an integer in [0, 4096]",
        ),
        ({"expansion_pass": 1.5}, "bad value 1.5 for 'expansion_pass'"),
        ({"expansion_pass": "x"}, "bad value 'x' for 'expansion_pass'"),
        ({"expansion_pass": 5000}, "expected an integer in [0, 4096]"),
        (
            {"expansion_pass": 16, "estimator": "direct"},
            "with estimator 'direct': the pass gives the expansion point of estimator series only",
        ),
        (
            {"expansion_pass": 16, "estimator": "series_recursive"},
            "with estimator 'series_recursive'",
        ),
    ],
)
def test_bad_values_are_refused_in_one_line(values, needle):
    with pytest.raises(SettingsError) as err:
        S.parse({"style": "gamma", "estimator": "series", **values})
    assert needle in str(err.value) and "\n" not in str(err.value)


def test_a_bare_render_is_refused_in_one_line(scene):
    """Without the pre-pass (integrator.render, which mi.render wraps in a RuntimeError) there is
    no b to use."""
    integ = api.make_integrator(
        "gamma", inner=4, estimator="series", expansion_pass=16, exposure=1.0
    )
    with pytest.raises(SettingsError) as err:
        integ.render(scene, scene.sensors()[0], 0, 1)
    assert "its pre-pass runs in styletrace's passes" in str(err.value) and "\n" not in str(
        err.value
    )
    with pytest.raises(RuntimeError) as err:
        mi.render(scene, integrator=integ, spp=1)
    assert isinstance(err.value.__cause__, SettingsError)


def test_cluster_renders_refuse_the_pass():
    """A cluster render's units are bare renders of one (tile, pass) on the workers: refused up
    front."""
    pytest.importorskip("ray")
    from types import SimpleNamespace

    from styletrace.errors import UsageError
    from styletrace.pipeline.ray_plan import Plan
    from styletrace.pipeline.ray_run import Render
    job = SimpleNamespace(values={"style": "gamma", "estimator": "series", "expansion_pass": "16"})
    with pytest.raises(UsageError) as err:
        Render(job, Plan(16, 16, 4, 0))
    assert "bad value '16' for 'expansion_pass' in a cluster render" in str(err.value)


def test_first_n_hits_takes_the_pass_at_the_first_level_only():
    """With two stylized levels the pass's children are level-0 children (each with its own
    level-1 estimate); the render's level 0 expands about the pass's b, level 1 keeps its in-lane
    pilot; same seed, same image."""
    def render():
        integ = api.make_integrator(
            "gamma",
            inner=(4, 2),
            estimator="series",
            expansion_pass=8,
            exposure=1.0,
            stylize="first_n_hits",
            stylize_depth=2,
        )
        img = api.render("cornell-box", integrator=integ, spp=1, width=12, height=12, seed=2)
        return img, integ
    (a, integ), (b, _) = render(), render()
    (moments,) = integ.expansion.maps.values()
    assert np.all(np.isfinite(a)) and np.array_equal(a, b)
    assert (
        np.all(moments.b_star() >= 0)
        and np.count_nonzero(moments.b_star()) > 0.5 * moments.b_star().size
    )
