"""Restyling a buffer equals a fresh render with the new style (same seed, same n), for every
style."""

import numpy as np
import pytest
from helpers.same_render import assert_same_render

import styletrace
from styletrace.errors import SceneError, SettingsError, StyleError, UsageError
from styletrace.frontends import api
from styletrace.lookdev.record import record, render_buffer
from styletrace.lookdev.restyle import restyle
from styletrace.pipeline.passes import PassSplit, Shot
from styletrace.scene.builtin import cornell_box
from styletrace.styles import style_class, style_names

W, H, SPP, INNER, SEED = 20, 14, 3, 2, 7
#: "up to float rounding": both images are float32 means of the same per-sample float32 values
RTOL, ATOL = 1e-5, 1e-6


@pytest.fixture(scope="module")
def buf():
    return render_buffer(
        "cornell-box", style="cel", spp=SPP, inner=INNER, seed=SEED, width=W, height=H
    )


def fresh(style, **kw):
    return styletrace.render(
        "cornell-box", style=style, spp=SPP, inner=INNER, seed=SEED, width=W, height=H, **kw
    )


def test_recorded_image_is_the_render(buf):
    assert_same_render(buf.image, fresh("cel"), SPP)
    np.testing.assert_allclose(restyle(buf), buf.image, rtol=RTOL, atol=ATOL)


@pytest.mark.parametrize("name", style_names())
def test_restyle_equals_a_fresh_render(buf, name):
    if style_class(name).per_sample:
        with pytest.raises(
            UsageError, match=f"style '{name}' cannot restyle: it applies g to every child"
        ):
            restyle(buf, style=name)
        return
    np.testing.assert_allclose(restyle(buf, style=name), fresh(name), rtol=RTOL, atol=ATOL)


@pytest.mark.parametrize(
    "name",
    [
        n
        for n in style_names()
        if "affine"
        in __import__("styletrace.config.estimator_registry", fromlist=["x"]).applicable(
            style_class(n)()
        )
    ],
)
def test_restyle_with_the_affine_estimator(buf, name):
    np.testing.assert_allclose(
        restyle(buf, style=name, estimator="affine"),
        fresh(name, estimator="affine"),
        rtol=RTOL,
        atol=ATOL,
    )


def test_restyle_with_new_parameters_changes_the_image_as_a_render_does(buf):
    kw = dict(thresholds=(0.05, 0.3), levels=(0.02, 0.2, 0.8))
    out = restyle(buf, **kw)  # the recorded style (cel), new parameters
    np.testing.assert_allclose(out, fresh("cel", **kw), rtol=RTOL, atol=ATOL)
    assert np.abs(out - buf.image).max() > 0.1


def test_several_passes_are_all_kept():
    """A pass of 2 spp and one of 1 spp (their own pass seeds), as `api.passes` renders them."""
    scene = api.load_scene("cornell-box", W, H)
    lanes = 2 * W * H
    *_, (prog, buf) = record(
        Shot(scene, api.make_integrator("cel", inner=INNER), SPP, SEED), PassSplit(lanes)
    )
    assert [p["spp"] for p in buf.header["passes"]] == [2, 1] and buf.camera_samples == W * H * SPP
    *_, want = api.passes(scene, api.make_integrator("gamma", inner=INNER), SPP, SEED, lanes)
    np.testing.assert_allclose(restyle(buf, style="gamma"), want.image, rtol=RTOL, atol=ATOL)


def object_scene(style, **params):
    scene = cornell_box(W, H)
    scene["large-box"]["bsdf"] = {
        "type": "styled",
        "style": style,
        "inner_samples": INNER,
        **params,
        "bsdf": {"type": "diffuse"},
    }
    return scene


def test_first_object_hit_restyles_the_styled_objects():
    kw = dict(style="identity", spp=SPP, seed=SEED, stylize="first_object_hit")
    buf = render_buffer(object_scene("cel"), **kw)
    assert buf.stylize == "first_object_hit" and [s["owner"] for s in buf.header["slots"]] == [
        "object"
    ]
    assert_same_render(buf.image, styletrace.render(object_scene("cel"), **kw), SPP)
    want = styletrace.render(object_scene("color_map", gradient="heat"), **kw)
    np.testing.assert_allclose(
        restyle(buf, style="color_map", gradient="heat"), want, rtol=RTOL, atol=ATOL
    )


@pytest.mark.parametrize(
    "kwargs,error,message",
    [
        (
            dict(stylize="first_n_hits", stylize_depth=2, inner=(2, 2)),
            SettingsError,
            "first_n_hits cannot be buffered",
        ),
        (dict(style="acp"), SettingsError, "style 'acp' cannot be buffered"),
        (dict(lines=True), SettingsError, "feature lines"),
        (dict(inner="2:8"), SettingsError, "a buffer keeps one fixed count of children"),
        (dict(aovs=True), SettingsError, "a buffer keeps the children's means, not the error AOVs"),
        (
            dict(style="gamma", estimator="series", expansion_pass=16),
            SettingsError,
            "not a pre-pass's expansion point",
        ),
    ],
)
def test_what_cannot_be_recorded_is_refused(kwargs, error, message):
    kwargs = {"style": "cel", "inner": 2, **kwargs}
    with pytest.raises(error, match=message):
        render_buffer("cornell-box", spp=1, width=8, height=8, **kwargs)


def test_a_film_other_than_rgb_is_refused():
    scene = cornell_box(8, 8)
    scene["sensor"]["film"]["pixel_format"] = "luminance"
    with pytest.raises(SceneError, match="pixel_format is 'y': buffers need an rgb film"):
        render_buffer(scene, style="cel", spp=1, inner=1)


def test_the_cap_on_camera_samples():
    with pytest.raises(UsageError, match="holds 256 camera samples, over the cap of 100"):
        render_buffer(
            "cornell-box", style="cel", spp=4, inner=1, width=8, height=8, max_camera_samples=100
        )


def test_what_cannot_restyle_is_refused(buf):
    with pytest.raises(
        UsageError, match="estimator 'series' cannot restyle: it needs the children themselves"
    ):
        restyle(buf, style="gamma", estimator="series")
    with pytest.raises(UsageError, match="the buffer holds the mean of n = 2 children"):
        restyle(buf, inner=4)
    with pytest.raises(UsageError, match="adaptive counts n0:n_max need a new render"):
        restyle(buf, inner="2:8")
    with pytest.raises(StyleError, match="bad value -1.0 for parameter 'gamma'"):
        restyle(buf, style="gamma", gamma=-1.0)
    closed = render_buffer("cornell-box", style="xtoon", spp=1, width=8, height=8)
    assert closed.header["slots"][0]["inner"] == 0
    with pytest.raises(
        UsageError, match="closed-form style 'xtoon' \\(0 children\\) and 'cel' needs n >= 1"
    ):
        restyle(closed, style="cel")
    restyle(closed, style="gooch")  # closed form to closed form is fine


def test_rays_that_miss_keep_the_environment():
    """The furnace: a sphere under a constant environment, which the missing camera samples see
    unstylized."""
    kw = dict(spp=2, inner=2, seed=SEED, width=16, height=16)
    buf = render_buffer("furnace", style="cel", **kw)
    missed = buf.arrays["slot"] < 0
    assert 0 < missed.mean() < 1 and np.all(buf.arrays["L_before"][:, missed] > 0)
    np.testing.assert_allclose(
        restyle(buf, style="sepia"),
        styletrace.render("furnace", style="sepia", **kw),
        rtol=RTOL,
        atol=ATOL,
    )


def test_restyle_sums_each_pixel_in_one_order(buf):
    """Every pixel holds SPP samples: restyling sums them in blocks, so repeated restyles agree
    to the bit (an atomic scatter-add, as Mitsuba's film uses, may not: see
    helpers/same_render.py)."""
    first = restyle(buf, style="gamma", gamma=1.7)
    for _ in range(30):
        np.testing.assert_array_equal(restyle(buf, style="gamma", gamma=1.7), first)


def test_a_restyle_with_new_parameters_chooses_the_auto_values_again():
    """The header names the values the pilot chose (`auto`); a restyle that changes the style's
    parameters chooses them again from the stored pilot, as a fresh render of the new values does
    (two levels need one threshold, not the three bands' two)."""
    kw = dict(spp=2, inner=4, seed=3, width=24, height=24)
    buf = styletrace.render_buffer("cornell-box", style="cel", **kw)
    assert set(buf.header["slots"][0]["auto"]) >= {"thresholds", "levels"}
    for params in ({"levels": "0.2,0.8"}, {"levels": "0.1,0.3,0.6,0.9"}, {"bands": 5}):
        fresh = styletrace.render("cornell-box", style="cel", denoise="off", **kw, **params)
        np.testing.assert_allclose(styletrace.restyle(buf, **params), fresh, rtol=1e-5, atol=1e-6)


def test_join_keeps_the_order_of_many_parts():
    """`join` (a buffer's pass parts, JOIN at a time): the same array as numpy's concatenation, for
    one part, one group and groups of groups."""
    from styletrace.gate import mi
    from styletrace.lookdev.restyle import JOIN, join
    rng = np.random.default_rng(3)
    for count in (1, JOIN, JOIN * JOIN + 3):
        host = [rng.random(int(rng.integers(1, 9))).astype(np.float32) for _ in range(count)]
        got = np.asarray(join([mi.Float(h) for h in host]))
        assert np.array_equal(got, np.concatenate(host))
