"""F12's Position, UV, Mist, Object Index, Material Index, Denoising Albedo and Emission passes
against Cycles' own on the same bpy scene: a floor and a box with pass indices and an emitting
square, under the World's mist. Where a pixel sees one surface the values agree; at edges the
renderers' samples differ, so only most pixels are held to that. (Not an area lamp: Cycles 5.0's
camera rays pass through it, styletrace's exported emitter is a surface they meet.)"""
import numpy as np
import pytest
import scenes as S
from test_data_passes import steady

SIZE = (48, 36)
#: the camera's field of view: a pixel is FOOT * depth wide (36 mm film, 35 mm lens, 48 pixels)
FOOT = 36.0 / 35.0 / SIZE[0]
#: the switches, Cycles' own, in `f12.DATA_PASSES` order
SWITCHES = ("use_pass_position", "use_pass_uv", "use_pass_mist", "use_pass_object_index",
            "use_pass_material_index", "use_pass_emit")
NAMES = ("Position", "UV", "Mist", "Object Index", "Material Index", "Denoising Albedo",
         "Emission")
EMIT = (0.5, 1.0, 2.0)


def build(falloff="LINEAR"):
    s = S.reset(SIZE[0])
    s.render.resolution_y = SIZE[1]
    floor_mat, _ = S.material("floor", Color=(0.8, 0.4, 0.2))
    box_mat, _ = S.material("box", Color=(0.1, 0.7, 0.3))
    glow, _ = S.material("glow", "ShaderNodeEmission", Color=EMIT, Strength=1.0)
    floor_mat.pass_index, box_mat.pass_index = 5, 9
    floor = S.plane(4, (0, 0, 0), mat=floor_mat)
    box = S.cube(1.0, (0.7, 0.4, 0.5), mat=box_mat)
    floor.pass_index, box.pass_index = 3, 7
    S.plane(0.6, (-0.9, 0.6, 0.3), mat=glow)
    S.light("SUN", (0, 0, 10), energy=2.0)
    S.camera((0, 0, 6.0), (0, 0, 0), lens=35)
    m = s.world.mist_settings
    m.start, m.depth, m.falloff = 5.0, 1.5, falloff
    layer = s.view_layers[0]
    for name in SWITCHES:
        setattr(layer, name, True)
    layer.use_pass_z = True
    layer.cycles.denoising_store_passes = True
    return s


def render_both(tmp_path, falloff="LINEAR"):
    build(falloff)
    st = S.styletrace(str(tmp_path / "st.exr"), 16, seed=1, denoise="off", style="identity")
    S.cycles(str(tmp_path / "cy.exr"), 16)
    return st, S.read_exr(str(tmp_path / "cy.exr"))


@pytest.fixture(scope="module")
def both(tmp_path_factory):
    return render_both(tmp_path_factory.mktemp("passes"))


def one_surface(st, cy):
    """Pixels where both see one surface: depth steady around them in both."""
    return steady(st["Depth"], 1e-3) & steady(cy["Depth"], 1e-3)


def report(name, st, cy, where, tol):
    err = np.abs(st[name] - cy[name]).max(-1)
    share = np.mean(err <= tol)
    print(f"{name}: {where.mean():.2f} of the pixels inside one surface, largest error there "
          f"{err[where].max():.2e}; {share:.3f} of all pixels within {tol}")
    return err, share


def test_every_pass_is_written_under_cycles_name(both):
    st, cy = both
    for name in NAMES:
        assert name in st and st[name].shape == cy[name].shape, name


def test_position_and_the_indices_are_the_first_samples(both):
    st, cy = both
    one = one_surface(st, cy)
    assert one.mean() > 0.5
    for name, tol in (("Object Index", 0), ("Material Index", 0)):
        err, share = report(name, st, cy, one, tol)
        assert err[one].max() <= tol and share > 0.93, name
    # both write one sample's point (Cycles' sample 0 lies at the pixel's centre, styletrace's
    # first is jittered in it): within a pixel's footprint of each other, and styletrace's
    # point is its Depth's (the camera looks down -z from height 6)
    depth = st["Depth"][..., 0]
    err, share = report("Position", st, cy, one, FOOT * 6.0)
    assert err[one].max() <= FOOT * 6.0 and share > 0.93
    seen = depth < 1e9
    np.testing.assert_allclose(6.0 - st["Position"][seen][:, 2], depth[seen], atol=1e-5)
    assert (st["Position"][~seen] == 0).all() and (cy["Position"][cy["Depth"][..., 0] > 1e9]
                                                   == 0).all()
    # each index is one object's or material's, never a blend, at edges too
    assert set(np.unique(st["Object Index"])) == {0.0, 3.0, 7.0}
    assert set(np.unique(st["Material Index"])) == {0.0, 5.0, 9.0}


def test_uv_mist_albedo_and_emission_are_means(both):
    st, cy = both
    one = one_surface(st, cy)
    for name, tol in (("Mist", 0.02), ("Emission", 1e-3)):
        err, share = report(name, st, cy, one, tol)
        assert err[one].max() <= tol and share > 0.9, name
    # a mean of 16 samples spread over the pixel: the floor's and the box's UVs change by 0.03
    # across a pixel (the small emitting square's by 0.2: left out)
    floor_box = one & (cy["Object Index"][..., 0] > 0)
    err, share = report("UV", st, cy, floor_box, 0.01)
    assert floor_box.mean() > 0.3 and err[floor_box].max() <= 0.01 and share > 0.9
    # Cycles' Denoising Albedo of an emission shader is its colour; the denoiser's guide
    # styletrace writes holds 1 there (docs/passes.md): compared off the emitter
    dark = one & (cy["Emission"].max(-1) == 0)
    err, _ = report("Denoising Albedo", st, cy, dark, 1e-3)
    assert dark.mean() > 0.5 and err[dark].max() <= 1e-3
    # edge pixels hold blends: UV's A is the share of samples that hit
    a = st["UV"][..., 2]
    assert ((a > 0) & (a < 1)).sum() > 10
    glowing = one & (np.abs(cy["Emission"] - EMIT).max(-1) < 1e-4)
    assert glowing.sum() > 3
    np.testing.assert_allclose(st["Emission"][glowing], np.tile(EMIT, (glowing.sum(), 1)),
                               atol=1e-4)


@pytest.mark.parametrize("falloff", ["QUADRATIC", "INVERSE_QUADRATIC"])
def test_mist_falloffs_match_cycles(tmp_path, falloff):
    st, cy = render_both(tmp_path, falloff)
    one = one_surface(st, cy)
    # means of 16 samples each side: a few pixels differ by 0.01, none by the 0.1 and more
    # that another falloff gives there
    err, share = report("Mist", st, cy, one, 0.02)
    assert err[one].max() <= 0.02 and np.median(err[one]) < 0.003 and share > 0.9
    empty = st["UV"][..., 2] == 0  # no sample met a surface: the world's mist is 1
    assert empty.sum() > 10 and (st["Mist"][empty] == 1).all()


def test_an_exported_xml_keeps_the_indices(tmp_path):
    """The XML export carries the pass indices in its shapes' ids: the command line's Object and
    Material Index passes of the file are F12's."""
    build()
    st = S.styletrace(str(tmp_path / "st.exr"), 4, seed=2, denoise="off", style="identity")
    xml = str(tmp_path / "scene.xml")
    assert S.bpy.ops.styletrace.export_xml(filepath=xml) == {"FINISHED"}
    from styletrace.frontends.api import load_scene
    from styletrace.kernel.data_passes import render_data_passes
    sc = load_scene(xml)
    ids = sorted(s.id() for s in sc.shapes())
    assert any(i.endswith("__ob3__ma5") for i in ids) and any(i.endswith("__ob7__ma9") for i in ids)
    mine = render_data_passes(sc, ["object_index", "material_index"], 4, 2)
    for key, name in (("object_index", "Object Index"), ("material_index", "Material Index")):
        assert np.array_equal(mine[key], st[name][..., 0]), key
