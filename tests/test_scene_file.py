"""Mitsuba XML scenes render as their authors meant (issue 8): the scene's integrator settings
carry over, -D parameters, resizing any film, the spp default, unknown integrators replaced, and
every film format."""
import os

import numpy as np
import pytest

import styletrace
from styletrace.errors import SceneError
from styletrace.frontends import api
from styletrace.frontends.cli import build_parser, cli_integrator, main
from styletrace.gate import mi
from styletrace.images import save_safely

styletrace.init()

#: Rec. 709 / sRGB primaries with a D65 white (IEC 61966-2-1): linear RGB -> CIE XYZ
RGB_TO_XYZ = np.array([[0.412453, 0.357580, 0.180423],
                       [0.212671, 0.715160, 0.072169],
                       [0.019334, 0.119193, 0.950227]])


def xml(
    integrator='<integrator type="path"><integer name="max_depth" value="6"/></integrator>',
    film='<integer name="width" value="12"/><integer name="height" value="8"/>',
    pixel_format="rgb",
    head='<default name="spp" value="3"/>',
):
    return f"""<scene version="3.0.0">{head}{integrator}
      <sensor type="perspective"><transform name="to_world"><lookat origin="0,0,4" target="0,0,0" \
up="0,1,0"/></transform>
        <sampler type="independent"><integer name="sample_count" value="$spp"/></sampler>
        <film type="hdrfilm">{film}<string name="pixel_format" value="{pixel_format}"/><rfilter \
type="box"/></film>
      </sensor>
      <shape type="sphere"><bsdf type="diffuse"><rgb name="reflectance" \
value="0.8,0.4,0.2"/></bsdf></shape>
      <shape type="rectangle"><transform name="to_world"><translate value="0,0,-3"/></transform>
        <emitter type="area"><rgb name="radiance" value="1,2,3"/></emitter></shape>
      <emitter type="constant"><rgb name="radiance" value="0.3,0.5,0.7"/></emitter></scene>"""


def write(tmp_path, text, name="s.xml"):
    path = tmp_path / name
    path.write_text(text)
    return str(path)


def read(path):
    bmp = mi.Bitmap(str(path))
    return bmp, np.array(bmp, dtype=np.float64).reshape(bmp.height(), bmp.width(), -1)


# ---- 4: the scene's integrator settings ----------------------------------------------------------
def args_of(*argv):
    return build_parser().parse_args(["render", *argv])


def test_cli_keeps_the_scenes_depths_and_hide_emitters_and_a_flag_wins(tmp_path):
    path = write(
        tmp_path,
        xml(
            '<integrator type="volpath"><integer name="max_depth" value="6"/>'
            '<integer name="rr_depth" value="3"/><boolean name="hide_emitters" value="true"/>'
            '</integrator>'
        ),
    )
    scene = api.load_scene(path)
    s = cli_integrator(scene, args_of(path), {}).settings
    assert (s.max_depth, s.rr_depth, s.hide_emitters, s.style.name) == (6, 3, True, "cel")
    s = cli_integrator(
        scene, args_of(path, "--max-depth", "2", "--hide-emitters", "false"), {}
    ).settings
    assert (s.max_depth, s.rr_depth, s.hide_emitters) == (2, 3, False)


# ---- 6: -D parameters, any film resized, spp -----------------------------------------------------
def test_defines_set_the_files_parameters(tmp_path):
    path = write(
        tmp_path,
        xml(
            integrator='<integrator type="path"><integer name="max_depth" value="$d"/>'
            '</integrator>',
            head='<default name="spp" value="3"/><default name="d" value="4"/>',
        ),
    )
    scene = api.load_scene(path, defines={"spp": 7, "d": "2"})
    assert api.scene_spp(scene) == 7 and api.carried_settings(scene)["max_depth"] == 2
    with pytest.raises(SceneError, match="uses no parameter nope: -D"):
        api.load_scene(path, defines={"nope": 1})


def test_a_define_used_only_by_a_resized_films_size_is_accepted(tmp_path):
    """The resize replaces `$w`; Mitsuba would refuse the define as unused in the edited text."""
    path = write(
        tmp_path,
        xml(
            film='<integer name="width" value="$w"/><integer name="height" value="8"/>',
            head='<default name="spp" value="3"/><default name="w" value="12"/>',
        ),
    )
    assert list(api.load_scene(path, 20, defines={"w": 5}).sensors()[0].film().size()) == [20, 8]
    assert list(api.load_scene(path, defines={"w": 5}).sensors()[0].film().size()) == [5, 8]


def test_width_and_height_resize_a_film_without_parameters(tmp_path):
    path = write(tmp_path, xml())
    assert list(api.load_scene(path, 20, 6).sensors()[0].film().size()) == [20, 6]
    assert list(api.load_scene(path, 20).sensors()[0].film().size()) == [20, 8]
    # a sensor without a film gets Mitsuba's default film at the new size
    no_film = (
        xml()
        .replace('<film type="hdrfilm">', "<!--")
        .replace('<rfilter type="box"/></film>', "-->")
    )
    assert list(
        api.load_scene(write(tmp_path, no_film, "n.xml"), 10, 4).sensors()[0].film().size()
    ) == [10, 4]
    with pytest.raises(SceneError, match="crop window"):
        api.load_scene(
            write(tmp_path, xml(film='<integer name="crop_width" value="4"/>'), "c.xml"), 10, 4
        )


def test_a_mesh_path_still_resolves_next_to_a_resized_scene(tmp_path):
    """The edited XML is loaded from text; relative file names resolve in the scene's folder as
    before."""
    (tmp_path / "m").mkdir()
    mi.load_dict({"type": "cube"}).write_ply(str(tmp_path / "m" / "cube.ply"))
    text = xml().replace(
        '<shape type="sphere">', '<shape type="ply"><string name="filename" value="m/cube.ply"/>'
    )
    cwd = os.getcwd()
    os.chdir("/")
    try:
        scene = api.load_scene(write(tmp_path, text), 6, 6)
    finally:
        os.chdir(cwd)
    assert any(s.class_name() == "PLYMesh" for s in scene.shapes())


def test_cli_spp_defaults_to_the_scenes_and_the_flag_wins(tmp_path, capsys):
    path = write(tmp_path, xml())
    out = str(tmp_path / "o.exr")
    assert main(["render", path, "-o", out, "--inner", "1"]) == 0
    assert "spp 3)" in capsys.readouterr().err
    assert main(["render", path, "-o", out, "--inner", "1", "--spp", "2", "-D", "spp=5"]) == 0
    assert "spp 2)" in capsys.readouterr().err
    assert main(["render", path, "-o", out, "--inner", "1", "-D", "spp=5", "--width", "5"]) == 0
    assert "spp 5)" in capsys.readouterr().err and read(out)[1].shape == (8, 5, 3)


# ---- includes: resized as Mitsuba expands them ---------------------------------------------------
def sensor_xml(fov=40):
    return (
        f'<sensor type="perspective"><float name="fov" value="{fov}"/><transform name="to_world">'
        f'<lookat origin="0,0,4" target="0,0,0" up="0,1,0"/></transform>'
        f'<sampler type="independent"><integer name="sample_count" value="2"/></sampler>'
        f'<film type="hdrfilm"><integer name="width" value="12"/><integer name="height" value="8"/>'
        f'<rfilter type="box"/></film></sensor>'
    )


LIGHTS = (
    '<shape type="rectangle"><transform name="to_world"><translate value="0,0,-3"/></transform>'
    '<emitter type="area"><rgb name="radiance" value="1,2,3"/></emitter></shape>'
    '<emitter type="constant"><rgb name="radiance" value="0.3,0.5,0.7"/></emitter>'
)


def scene_xml(body):
    return f'<scene version="3.0.0">{body}</scene>'


def same_as_unresized(path):
    """Resized to its own size (the included files expanded, the text loaded from a string) the
    scene renders bit-identically to Mitsuba's own load of the file."""
    own = api.render(path, style="identity", inner=1, spp=2, seed=5)
    resized = api.render(path, style="identity", inner=1, spp=2, seed=5, width=12, height=8)
    np.testing.assert_array_equal(resized, own)
    return own


def test_resize_reaches_a_sensor_in_an_included_file(tmp_path):
    write(tmp_path, scene_xml(sensor_xml()), "camera.xml")
    path = write(
        tmp_path,
        scene_xml(
            '<include filename="camera.xml"/>'
            '<shape type="sphere"><bsdf type="diffuse"/></shape>' + LIGHTS
        ),
    )
    assert list(api.load_scene(path, 20, 6).sensors()[0].film().size()) == [20, 6]
    same_as_unresized(path)


def test_nested_includes_resolve_next_to_the_including_file(tmp_path):
    """main.xml includes $parts/all.xml (a <default>), which includes camera.xml: Mitsuba takes
    the one next to all.xml (fov 30), not the one next to main.xml (fov 80); an included
    non-scene root (a BSDF) takes the include's place under its name."""
    (tmp_path / "parts").mkdir()
    write(tmp_path, scene_xml(sensor_xml(80)), "camera.xml")
    write(tmp_path / "parts", scene_xml(sensor_xml(30)), "camera.xml")
    write(
        tmp_path / "parts",
        '<bsdf version="3.0.0" type="diffuse"><rgb name="reflectance" value="0.8,0.4,0.2"/></bsdf>',
        "red.xml",
    )
    write(
        tmp_path / "parts",
        scene_xml(
            '<include filename="camera.xml"/><shape type="sphere">'
            '<include filename="red.xml" name="bsdf"/></shape>'
        ),
        "all.xml",
    )
    path = write(
        tmp_path,
        scene_xml(
            '<default name="parts" value="parts"/><include filename="$parts/all.xml"/>' + LIGHTS
        ),
    )
    resized = api.load_scene(path, 20, 6)
    fov = mi.traverse(resized.sensors()[0])["x_fov"]
    assert abs(float(fov[0] if hasattr(fov, "__len__") else fov) - 30.0) < 1e-3
    own = same_as_unresized(path)
    assert own[..., 0].max() > 2 * own[..., 2].min()  # the red BSDF arrived
    with pytest.raises(
        SceneError, match=r"cannot resize scene file .*included file 'nowhere/all.xml' not found"
    ):
        api.load_scene(path, 20, 6, defines={"parts": "nowhere"})


def test_an_included_texture_resolves_as_mitsuba_resolves_it(tmp_path):
    """An included file in a subfolder: its texture path is relative to the scene's folder, where
    Mitsuba 3.9.1 resolves the plugins an included file names (not the included file's folder,
    nor one its <path> adds: the include's resolver ends with it). Resized, the scene loads and
    renders the same; a path relative to the subfolder alone fails with one line either way, as
    in Mitsuba."""
    sub = tmp_path / "looks"
    sub.mkdir()
    check = np.zeros((4, 4, 3), dtype=np.float32)
    check[::2, ::2] = check[1::2, 1::2] = 1.0
    mi.Bitmap(check).convert(mi.Bitmap.PixelFormat.RGB, mi.Struct.Type.UInt8, True).write(
        str(sub / "check.png")
    )

    def look(texture, extra=""):
        return scene_xml(
            f'{extra}<bsdf type="diffuse" id="look"><texture type="bitmap" name="reflectance">'
            f'<string name="filename" value="{texture}"/><string name="filter_type" '
            f'value="nearest"/>'
            f'</texture></bsdf>'
        )

    main_text = scene_xml(sensor_xml() + '<include filename="looks/look.xml"/>'
                          '<shape type="rectangle"><ref id="look"/></shape>' + LIGHTS)
    write(sub, look("looks/check.png"), "look.xml")
    path = write(tmp_path, main_text)
    img = same_as_unresized(path)
    assert img.mean(axis=2).std() > 0.05                       # the checker shows
    for extra in ("", '<path value="."/>'):
        write(sub, look("check.png", extra), "look.xml")
        for size in ((None, None), (12, 8)):
            with pytest.raises(SceneError, match="check.png"):
                api.load_scene(path, *size)


# ---- 7: an integrator Mitsuba does not know ------------------------------------------------------
def test_unknown_integrator_is_replaced_keeping_its_depths(tmp_path, capsys):
    path = write(
        tmp_path,
        xml(
            '<integrator type="sre"><integer name="max_depth" value="3"/>'
            '<integer name="rr_depth" value="2"/><string name="style" value="toon"/>'
            '<float name="sharpness" value="2"/></integrator>'
        ),
    )
    with pytest.warns(
        api.SceneWarning,
        match="integrator 'sre' is not a Mitsuba plugin: rendering with stylized, "
        "keeping max_depth=3, rr_depth=2; dropped style, sharpness",
    ):
        scene = api.load_scene(path)
    assert api.carried_settings(scene) == {"max_depth": 3, "rr_depth": 2}
    out = str(tmp_path / "o.png")
    assert main(["render", path, "-o", out, "--inner", "1", "--spp", "1"]) == 0
    err = capsys.readouterr().err.splitlines()
    assert [line for line in err if "warning" in line] == [
        f"styletrace: warning: scene file '{path}': integrator 'sre' is not a Mitsuba plugin: "
        f"rendering with "
        f"stylized, keeping max_depth=3, rr_depth=2; dropped style, sharpness"
    ]


# ---- 5: every pixel format of hdrfilm ------------------------------------------------------------
@pytest.fixture(scope="module")
def rgb_reference(tmp_path_factory):
    folder = tmp_path_factory.mktemp("rgb")
    path = write(folder, xml())
    return api.render(path, style="identity", inner=1, spp=4, seed=7)


@pytest.mark.parametrize("pixel_format, channels", [
    ("rgb", "RGB"), ("rgba", "RGBA"), ("luminance", "Y"), ("luminance_alpha", "YA"), ("xyz", "XYZ"),
    ("xyza", "XYZA")])
def test_every_pixel_format_is_written_as_the_film_asks(
    tmp_path, rgb_reference, pixel_format, channels
):
    """Same seed, same samples: the film's channels are the RGB render converted (Y and XYZ by
    the sRGB/Rec. 709 matrix), and alpha is 1 everywhere (the sky is visible)."""
    path = write(tmp_path, xml(pixel_format=pixel_format))
    out = tmp_path / "o.exr"
    assert (
        main(
            [
                "render",
                path,
                "-o",
                str(out),
                "--style",
                "identity",
                "--inner",
                "1",
                "--spp",
                "4",
                "--seed",
                "7",
                "-q",
            ]
        )
        == 0
    )
    bmp, img = read(out)
    assert bmp.pixel_format().name == channels
    want = {"R": rgb_reference[..., 0], "G": rgb_reference[..., 1], "B": rgb_reference[..., 2],
            "A": np.ones(rgb_reference.shape[:2])}
    xyz = rgb_reference @ RGB_TO_XYZ.T
    want.update({"X": xyz[..., 0], "Y": xyz[..., 1], "Z": xyz[..., 2]})
    for i, c in enumerate(channels):
        np.testing.assert_allclose(img[..., i], want[c], rtol=2e-3, atol=1e-5, err_msg=c)


def test_alpha_is_zero_where_a_hidden_sky_is_seen(tmp_path):
    path = write(
        tmp_path,
        xml(
            '<integrator type="path"><boolean name="hide_emitters" value="true"/></integrator>',
            pixel_format="rgba",
        ),
    )
    img = api.render(path, style="identity", inner=1, spp=2)
    assert img.shape == (8, 12, 4)
    assert img[0, 0, 3] == 0.0 and np.all(img[0, 0] == 0.0) and img[4, 6, 3] == 1.0


def test_luminance_png_is_grey_and_xyz_png_is_refused_before_rendering(tmp_path, capsys):
    out = tmp_path / "o.png"
    assert (
        main(
            [
                "render",
                write(tmp_path, xml(pixel_format="luminance")),
                "-o",
                str(out),
                "--spp",
                "1",
                "--inner",
                "1",
                "-q",
            ]
        )
        == 0
    )
    assert mi.Bitmap(str(out)).pixel_format() == mi.Bitmap.PixelFormat.Y
    assert (
        main(
            [
                "render",
                write(tmp_path, xml(pixel_format="xyz"), "x.xml"),
                "-o",
                str(tmp_path / "x.png"),
            ]
        )
        == 2
    )
    assert "XYZ images are written as .exr only" in capsys.readouterr().err
    assert not (tmp_path / "x.png").exists()


def test_a_failed_fallback_leaves_no_empty_file(tmp_path, monkeypatch):
    import tempfile
    monkeypatch.setattr(tempfile, "tempdir", str(tmp_path))
    # 2 channels are no rgb image: the write and the fallback both fail
    with pytest.raises(ValueError):
        save_safely(np.zeros((2, 2, 2), np.float32), str(tmp_path / "o.exr"))
    assert os.listdir(tmp_path) == []


# ---- an integrator chosen through a <default>, Mitsuba's convention ------------------------------
FLOATING_SPHERE = """<scene version="3.0.0">
  <default name="integrator" value="direct"/>
  <integrator type="$integrator"/>
  <sensor type="perspective"><float name="fov" value="30"/>
    <transform name="to_world"><lookat origin="0,0.4,0" target="0,2.5,0" up="0,0,1"/></transform>
    <sampler type="independent"><integer name="sample_count" value="4"/></sampler>
    <film type="hdrfilm"><integer name="width" value="8"/><integer name="height" value="8"/>
      <string name="pixel_format" value="rgb"/><rfilter type="box"/></film>
  </sensor>
  <shape type="sphere"><point name="center" x="0" y="2.5" z="0"/><float name="radius" value="1"/>
    <bsdf type="diffuse"><rgb name="reflectance" value="0.5,0.5,0.5"/></bsdf></shape>
  <shape type="rectangle"><transform name="to_world"><scale value="10"/><rotate x="1" \
angle="-90"/></transform>
    <bsdf type="diffuse"><rgb name="reflectance" value="0.5,0.5,0.5"/></bsdf></shape>
  <emitter type="directional"><vector name="direction" x="0" y="-1" z="0"/>
    <rgb name="irradiance" value="1,1,1"/></emitter>
</scene>"""


def test_an_integrator_chosen_by_a_default_renders_as_that_integrator(tmp_path, capsys):
    """A sphere floating over a lit plane, seen from below (every pixel shows its underside),
    under a directional light from straight above, integrator `direct` through `$integrator`: the
    underside has no direct light, so it is exactly 0 in Mitsuba's `direct` and in styletrace's
    identity render (it was 0.08: the literal '$integrator' was taken for an unknown plugin and
    replaced by an unbounded path tracer). `-D integrator=path` picks `path`: the light the plane
    reflects onto the underside appears."""
    path = write(tmp_path, FLOATING_SPHERE)
    mitsuba_direct = np.asarray(mi.render(mi.load_file(path), seed=1))
    assert np.all(mitsuba_direct == 0)
    out = str(tmp_path / "o.exr")
    assert main(["render", path, "-o", out, "--style", "identity", "--inner", "1"]) == 0
    underside = read(out)[1]
    assert underside.max() == 0, (
        f"the underside is {underside.max():.3f} where Mitsuba's direct gives 0"
    )
    assert "warning" not in capsys.readouterr().err
    assert (
        main(
            [
                "render",
                path,
                "-o",
                out,
                "--style",
                "identity",
                "--inner",
                "1",
                "-D",
                "integrator=path",
            ]
        )
        == 0
    )
    bounced = read(out)[1]
    mitsuba_path = np.asarray(mi.render(mi.load_file(path, integrator="path"), spp=64, seed=1))
    assert (
        mitsuba_path.mean() > 0.03
        and abs(bounced.mean() - mitsuba_path.mean()) < 0.25 * mitsuba_path.mean()
    )


def test_a_comment_with_a_double_hyphen_is_read_as_mitsuba_reads_it(tmp_path):
    """XML forbids "--" inside a comment; Mitsuba's parser accepts it (a licence header written
    that way), so the file is resized and rendered all the same."""
    import numpy as np
    path = tmp_path / "dashes.xml"
    path.write_text(
        '<!--\n-- SPDX-License-Identifier: Apache-2.0\n  -->\n<scene version="3.0.0">'
        '<sensor type="perspective"><film type="hdrfilm"><integer name="width" value="8"/>'
        '<integer name="height" value="8"/></film></sensor><shape type="sphere"/>'
        '<emitter type="constant"/></scene>'
    )
    img = styletrace.render(str(path), style="identity", width=6, height=4, spp=1)
    assert img.shape == (4, 6, 3) and np.isfinite(img).all()
