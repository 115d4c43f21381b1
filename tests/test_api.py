"""The Python API: scene loading, integrator construction, rendering in passes."""
import numpy as np
import pytest

import styletrace
from styletrace.errors import SettingsError, StyleError, UsageError
from styletrace.frontends import api
from styletrace.gate import mi


def test_render_returns_linear_float32_hwc():
    img = styletrace.render(
        "cornell-box", style="cel", spp=2, inner=2, width=20, height=12, levels=(0.3, 0.9)
    )
    assert img.dtype == np.float32 and img.shape == (12, 20, 3) and np.isfinite(img).all()


def test_passes_average_is_weighted_by_samples():
    """Unequal passes (4 + 2 spp) combine as (4 a + 2 b) / 6, each pass with its own derived
    seed (with independent samples; `owen_sobol` passes continue one sequence instead:
    tests/kernel/test_owen_sobol_sampler.py)."""
    scene = api.load_scene("cornell-box", 8, 8, sampler="independent")
    integ = api.make_integrator("identity", inner=1)
    progress = list(api.passes(scene, integ, 6, seed=5, lanes_per_pass=4 * 64))
    assert [p.spp_done for p in progress] == [4, 6]
    a = np.array(
        mi.render(scene, integrator=integ, spp=4, seed=api.pass_seed(5, 0)), dtype=np.float64
    )
    b = np.array(
        mi.render(scene, integrator=integ, spp=2, seed=api.pass_seed(5, 1)), dtype=np.float64
    )
    np.testing.assert_allclose(
        progress[-1].image, ((4 * a + 2 * b) / 6).astype(np.float32), rtol=1e-6
    )
    assert api.pass_count(scene, 6, 4 * 64) == 2


def test_pass_seeds_differ():
    seeds = {api.pass_seed(s, i) for s in range(4) for i in range(64)}
    assert len(seeds) == 4 * 64


@pytest.mark.parametrize("scene,kwargs,message", [
    ("no-such", {}, "unknown scene 'no-such'"),
    ("missing.xml", {}, "scene file 'missing.xml' does not exist"),
    ({"type": "scene", "s": {"type": "spheer"}}, {}, "cannot load scene dict"),
    ({"type": "scene"}, {"width": 8}, "width/height apply to built-in scenes and XML files"),
])
def test_scene_errors(scene, kwargs, message):
    with pytest.raises(api.SceneError, match=message):
        api.load_scene(scene, **kwargs)


def test_loaded_scene_cannot_be_resized():
    scene = api.load_scene("furnace", 8, 8)
    assert api.load_scene(scene, 8, 8) is scene
    with pytest.raises(api.SceneError, match="cannot change an already loaded"):
        api.load_scene(scene, 16, 8)


def test_make_integrator_validates_before_mitsuba():
    with pytest.raises(StyleError, match="bad value 'x' for parameter 'gamma'"):
        api.make_integrator("gamma", gamma="x")
    with pytest.raises(SettingsError, match="expected 1 or 2 counts"):
        api.make_integrator("cel", inner=(2, 3, 4), stylize="first_n_hits", stylize_depth=2)
    with pytest.raises(SettingsError, match="stylize_depth"):
        api.make_integrator("cel", stylize_depth=2)
    with pytest.raises(SettingsError, match="the integrator's own style must be identity"):
        api.make_integrator("cel", stylize="first_object_hit")


def test_gradient_given_as_stops():
    integ = api.make_integrator("color_map", gradient=[(0, (0, 0, 0)), (1, (1, 0.5, 0))])
    assert "0:0,0,0;1:1,0.5,0" in integ.settings.style.describe()


@pytest.mark.parametrize(
    "kwargs,error,message",
    [
        (
            dict(spp="16"),
            styletrace.UsageError,
            r"bad value '16' for spp: expected an integer in \[1, 4294967295\]",
        ),
        (dict(spp=1.5), styletrace.UsageError, "bad value 1.5 for spp"),
        (
            dict(seed=None),
            styletrace.UsageError,
            r"bad value None for seed: expected an integer in \[0, 4294967295\]",
        ),
        (dict(seed=2**32), styletrace.UsageError, "bad value 4294967296 for seed"),
        (dict(integrator="path"), styletrace.UsageError, "bad value 'path' for integrator"),
        (dict(inner=[2.7]), SettingsError, "bad value 2.7 for 'inner_samples'"),
        (
            dict(scene={"type": "scene", "s": {"type": "sphere"}}),
            styletrace.SceneError,
            "the scene dict has no sensor",
        ),
        (
            dict(scene={"type": "sphere"}),
            styletrace.SceneError,
            "the scene dict is a Sphere, not a scene",
        ),
    ],
)
def test_render_arguments_are_checked(kwargs, error, message):
    call = {"scene": "furnace", "width": 4, "height": 4, "spp": 1, **kwargs}
    if isinstance(call["scene"], dict):
        del call["width"], call["height"]
    with pytest.raises(error, match=message):
        styletrace.render(**call)


def test_the_largest_seed_is_its_own_image():
    """Seeds are 32-bit: 2^32 - 1 renders and differs from seed 0 (2^32 would alias 0 and is
    refused)."""
    a = styletrace.render("cornell-box", width=8, height=8, spp=1, seed=0)
    b = styletrace.render("cornell-box", width=8, height=8, spp=1, seed=2 ** 32 - 1)
    assert not np.array_equal(a, b)


def test_a_scene_file_without_a_sensor_is_a_scene_error(tmp_path):
    path = tmp_path / "empty.xml"
    path.write_text('<scene version="3.0.0"/>')
    with pytest.raises(styletrace.SceneError, match="has no sensor"):
        api.load_scene(str(path))


def test_tiles_cover_the_image_once_with_one_size():
    layout = api.tiles(24, 16, max_pixels=120)
    cover = np.zeros((16, 24), int)
    for t in layout:
        assert t.size == layout[0].size
        window = np.zeros((t.size[1], t.size[0]), int)
        window[t.keep] = 1
        cover[t.dest] += window[t.keep]
        assert 0 <= t.offset[0] <= 24 - t.size[0] and 0 <= t.offset[1] <= 16 - t.size[1]
    assert (cover == 1).all()
    assert len(api.tiles(1024, 1024)) == 1 and len(api.tiles(8192, 8192)) == 64


def test_a_tiled_render_matches_mitsubas_own_crop_windows(monkeypatch):
    """Tiles are crop windows: each must equal Mitsuba rendering that window of the film (its own
    crop_offset/crop_width properties) with the tile's seed (independent samples); shifted edge
    tiles keep only their new pixels."""
    from styletrace.pipeline import passes as pass_loop  # the pass loop reads its own constants
    monkeypatch.setattr(pass_loop, "LANES_PER_PASS", 120)
    monkeypatch.setattr(pass_loop, "TILE_SIDE", 10)
    scene = api.load_scene("cornell-box", 24, 16, sampler="independent")
    # explicit: no pilot
    integ = api.make_integrator("cel", inner=2, thresholds=(0.5,), levels=(0.4, 0.95))
    layout = api.tiles(24, 16)
    assert len(layout) == 6 and layout[0].size == (10, 12)
    progress = list(api.passes(scene, integ, 2, seed=3, lanes_per_pass=1 << 20))
    assert [p.spp_done for p in progress] == [0] * 5 + [2]
    expect = np.zeros((16, 24, 3), np.float32)
    for index, tile in enumerate(layout):
        d = api.scene_dict("cornell-box", 24, 16, sampler="independent")
        d["sensor"]["film"].update(crop_offset_x=tile.offset[0], crop_offset_y=tile.offset[1],
                                   crop_width=tile.size[0], crop_height=tile.size[1])
        img = np.array(
            mi.render(mi.load_dict(d), integrator=integ, spp=2, seed=api.pass_seed(3, index))
        )
        expect[tile.dest] = img[..., :3][tile.keep]
    np.testing.assert_allclose(progress[-1].image, expect, rtol=1e-6, atol=0)
    assert tuple(scene.sensors()[0].film().crop_size()) == (24, 16)  # the film is left as it was


def test_memory_is_checked_up_front(monkeypatch):
    from styletrace.pipeline import passes as pass_loop
    monkeypatch.setattr(pass_loop, "memory_available", lambda: 1 << 30)
    api.check_memory(1024, 1024)
    with pytest.raises(
        UsageError, match=r"image 8192x8192 is too large: it needs about \d+\.\d GiB"
    ):
        api.check_memory(8192, 8192)
    scene = api.load_scene("furnace", 8, 8)
    monkeypatch.setattr(pass_loop, "memory_available", lambda: 1000)
    with pytest.raises(UsageError, match="image 8x8 is too large"):
        next(api.passes(scene, api.make_integrator("identity", inner=1), 1))


def test_the_split_into_passes_depends_only_on_the_counts():
    assert api.pass_size(64, 64, 100) == (api.tiles(64, 64), 100)
    assert api.pass_size(2048, 2048, 100)[1] == 1 and len(api.pass_size(2048, 2048, 100)[0]) == 4
    assert api.pass_size(64, 64, 100, pass_spp=7)[1] == 7


def test_the_default_style_is_identity_in_python_and_cel_on_the_command_line(capsys, tmp_path):
    """The one default front ends do not share (docs/look.md, render()'s docstring): Python, the
    `stylized` plugin and Blender render physically based; the command line and the preview start
    from cel."""
    from styletrace.config.settings import COMMAND_LINE_STYLE, PROPERTIES
    from styletrace.frontends.cli import main
    small = dict(width=8, height=8, spp=2, denoise="off")
    np.testing.assert_array_equal(styletrace.render("furnace", **small),
                                  styletrace.render("furnace", style="identity", **small))
    assert next(p for p in PROPERTIES if p.name == "style").default == "identity"
    assert main(["render", "furnace", "--width", "8", "--height", "8", "--spp", "2", "--denoise",
                 "off", "-o", str(tmp_path / "cel.exr")]) == 0
    assert f", {COMMAND_LINE_STYLE}(" in capsys.readouterr().err.splitlines()[-1]
    assert COMMAND_LINE_STYLE == "cel"
