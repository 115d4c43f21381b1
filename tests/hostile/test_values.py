"""Hostile values: every input the front ends accept either renders a finite image or is refused
with one line.

The corpus lists command lines and API calls with the exception type (exit status 2 on the command
line) and a fragment of the message they must give. Issue 13, points 6-8: each case here once ended
in a traceback, an IndexError, a silently truncated value or a NaN/inf image.
"""
import math
import os

import numpy as np
import pytest

import styletrace
from styletrace.config import estimator_registry as estimation
from styletrace.errors import SceneError, SettingsError, StyleError, UsageError
from styletrace.frontends import api
from styletrace.frontends.cli import main
from styletrace.styles import style_class, style_names

BLACKBODY_XML = """<scene version="3.0.0">
  <sensor type="perspective"><film type="hdrfilm"><integer name="width" value="4"/>
    <integer name="height" value="4"/></film></sensor>
  <emitter type="constant"><spectrum type="blackbody" name="radiance"><float name="temperature" \
value="5000"/>
  </spectrum></emitter>
  <shape type="sphere"><transform name="to_world"><translate z="5"/></transform></shape>
</scene>"""
NO_SENSOR_XML = '<scene version="3.0.0"><shape type="sphere"/></scene>'
EMPTY_XML = '<scene version="3.0.0"/>'

# command line arguments -> the fragment of the one-line error (exit status 2)
CLI = [
    (
        ["--style", "gamma", "--set", "gamma=inf"],
        "for parameter 'gamma': expected a number in [0.1, 1e+06]",
    ),
    (
        ["--style", "reinhard", "--set", "white=inf"],
        "for parameter 'white': expected a number in (0, 1000]",
    ),
    (
        ["--style", "exp_tone", "--set", "exposure=800"],
        "for parameter 'exposure': expected a number in (0, 87]",
    ),
    (["--style", "hatching", "--set", "angle=inf"], "for parameter 'angle'"),
    (["--style", "tie_dye", "--set", "domain_max=inf"], "for parameter 'domain_max'"),
    (["--style", "tie_dye", "--set", "domain_max=5000"], "cosine's argument"),
    (["--style", "tie_dye", "--set", "phases=1e30"], "for parameter 'phases'"),
    (["--style", "tie_dye", "--set", "frequencies=1e4"], "must stay below 16384"),
    (["--style", "contrast", "--set", "c=inf"], "for parameter 'c'"),
    (["--style", "contrast", "--set", "c=1e300"], "for parameter 'c'"),
    (["--style", "contrast", "--set", "pivot=inf"], "for parameter 'pivot'"),
    (["--style", "contrast", "--set", "pivot=-inf"], "for parameter 'pivot'"),
    (["--style", "contrast", "--set", "pivot=nan"], "for parameter 'pivot'"),
    (["--style", "gooch", "--set", "light_dir=inf"], "for parameter 'light_dir'"),
    (["--style", "gooch", "--set", "light_dir=1e-200"], "a non-zero 3D vector"),
    (["--style", "gooch", "--set", "k_d=inf"], "for parameter 'k_d'"),
    (["--style", "gooch", "--set", "alpha=1e300"], "for parameter 'alpha'"),
    (
        ["--style", "color_map", "--set", "gradient=0:#000000;nan:#ffffff"],
        "finite positions that strictly increase",
    ),
    (["--style", "color_map", "--set", "gradient=0:#000000;1:inf,0,0"], "bad gradient"),
    (
        ["--style", "color_map", "--set", "gradient=0:#000000;1e-40:#ffffff"],
        "finite positions that strictly increase",
    ),
    (["--style", "hatching", "--set", "sets=1e400"], "for parameter 'sets'"),
    (["--max-depth", "4294967296"], "for --max-depth: expected an integer in [-1, 4294967294]"),
    (["--rr-depth", str(2**40)], "for --rr-depth: expected an integer in [1, 4294967294]"),
    (["--set", "samples_per_pass=0"], "for 'samples_per_pass'"),
    (["--set", "samples_per_pass=4"], "--pass-spp"),
    (
        ["--stylize", "first_n_hits", "--stylize-depth", "17"],
        "for --stylize-depth: expected an integer in [1, 16]",
    ),
    (["--stylize", "first_n_hits", "--stylize-depth", "1000"], "expected an integer in [1, 16]"),
    (["--inner", "4294967296"], "for --inner"),
    (["--seed", str(2**32)], "for --seed: expected an integer in [0, 4294967295]"),
    (["--seed", "-1"], "for --seed"),
    (["SCENE:blackbody"], "'blackbody' spectrum needs a spectral variant"),
    (["SCENE:no_sensor"], "has no sensor"),
    (["SCENE:empty"], "has no sensor"),
]


@pytest.fixture
def scenes(tmp_path):
    files = {}
    for name, text in (
        ("blackbody", BLACKBODY_XML),
        ("no_sensor", NO_SENSOR_XML),
        ("empty", EMPTY_XML),
    ):
        files[name] = tmp_path / f"{name}.xml"
        files[name].write_text(text)
    return files


@pytest.mark.parametrize("args,fragment", CLI, ids=[" ".join(a) for a, _ in CLI])
def test_command_line_refuses_with_one_line(args, fragment, scenes, tmp_path, capsys):
    # XML files fix their size
    size = [] if args[0].startswith("SCENE:") else ["--width", "4", "--height", "4"]
    args = [str(scenes[a.split(":")[1]]) if a.startswith("SCENE:") else a for a in args]
    out = tmp_path / "out.exr"
    code = main(["render", *args, *size, "--spp", "1", "-q", "-o", str(out)])
    err = capsys.readouterr().err
    assert code == 2, err
    assert err.startswith("styletrace: error: ") and err.count("\n") == 1, err
    assert fragment in err, err
    assert not out.exists()


# Python API calls -> (exception type, fragment naming the argument and what is allowed)
API = [
    (dict(spp="16"), UsageError, "bad value '16' for spp: expected an integer in [1, "),
    (dict(spp=1.5), UsageError, "bad value 1.5 for spp"),
    (dict(spp=True), UsageError, "bad value True for spp"),
    (dict(spp=0), UsageError, "bad value 0 for spp"),
    (
        dict(seed=None),
        UsageError,
        "bad value None for seed: expected an integer in [0, 4294967295]",
    ),
    (dict(seed=2**32), UsageError, "bad value 4294967296 for seed"),
    (dict(seed=-1), UsageError, "bad value -1 for seed"),
    (dict(seed=3.0), UsageError, "bad value 3.0 for seed"),
    (
        dict(integrator="path"),
        UsageError,
        "bad value 'path' for integrator: expected None or an mi.Integrator",
    ),
    (
        dict(scene={"type": "scene", "s": {"type": "sphere"}}),
        SceneError,
        "the scene dict has no sensor",
    ),
    (dict(scene={"type": "scene"}), SceneError, "the scene dict has no sensor"),
    (dict(scene={"type": "sphere"}), SceneError, "the scene dict is a Sphere, not a scene"),
    (dict(scene=5), SceneError, "bad scene 5: expected a built-in name"),
    (
        dict(inner=[2.7]),
        SettingsError,
        "bad value 2.7 for 'inner_samples': expected an integer in [1, ",
    ),
    (dict(inner="2.7"), SettingsError, "for 'inner_samples'"),
    (dict(stylize="first_n_hits", stylize_depth=1000), SettingsError, "for 'stylize_depth'"),
    (dict(max_depth=2**32), SettingsError, "for 'max_depth'"),
    (dict(samples_per_pass=2), SettingsError, "for 'samples_per_pass'"),
    (dict(style="exp_tone", exposure=800.0), StyleError, "for parameter 'exposure'"),
    (dict(style="gamma", gamma=math.inf), StyleError, "for parameter 'gamma'"),
    (dict(style="gamma", gamma=0.01), StyleError, "for parameter 'gamma'"),
    (dict(style="reinhard", white=3e5), StyleError, "for parameter 'white'"),
    (dict(style="gooch", light_dir=(math.nan, 0.0, 1.0)), StyleError, "for parameter 'light_dir'"),
    (
        dict(style="color_map", gradient=[(0.0, (0, 0, 0)), (math.nan, (1, 1, 1))]),
        StyleError,
        "bad gradient",
    ),
]


@pytest.mark.parametrize("kwargs,error,fragment", API, ids=[repr(k) for k, _, _ in API])
def test_api_refuses_with_one_line(kwargs, error, fragment):
    call = {"scene": "furnace", "width": 4, "height": 4, "spp": 1, **kwargs}
    if isinstance(call["scene"], dict):
        call.pop("width"), call.pop("height")
    with pytest.raises(error) as info:
        styletrace.render(**call)
    msg = str(info.value)
    assert fragment in msg and "\n" not in msg, msg


@pytest.mark.parametrize("name", ["blackbody", "no_sensor", "empty"])
def test_unrenderable_scene_files_are_refused_when_loaded(name, scenes):
    with pytest.raises(SceneError, match="has no sensor|blackbody") as info:
        api.load_scene(str(scenes[name]))
    assert "\n" not in str(info.value)


def test_passes_refuses_a_scene_without_a_sensor():
    scene = api.load_scene("furnace", 4, 4)
    bare = __import__("mitsuba").load_dict({"type": "scene"})
    with pytest.raises(SceneError, match="has no sensor"):
        next(api.passes(bare, api.make_integrator(), 1))
    with pytest.raises(UsageError, match="for seed"):
        next(api.passes(scene, api.make_integrator(), 1, seed=2 ** 32))


def _edges(p):
    """The extreme values `p` accepts: both ends of its range (just inside an open end)."""
    lo, hi = p.bounds()
    low = (1e-30 if lo == 0 else lo * (1 + 1e-6)) if p.low_open else lo
    return [hi, low]


EDGES = [(name, p.name, v, est) for name in style_names() for p in style_class(name).params
         if p.kind in ("float", "color", "vector", "floats", "int") for v in _edges(p)
         for est in estimation.applicable(style_class(name)())]


@pytest.fixture(scope="module")
def box():
    return api.load_scene("cornell-box", 8, 8)


@pytest.mark.parametrize(
    "style,param,value,estimator", EDGES, ids=[f"{s}-{p}={v:g}-{e}" for s, p, v, e in EDGES]
)
def test_accepted_extremes_render_finite_images(style, param, value, estimator, box):
    """Every value a parameter accepts, at the ends of its range, renders finite radiance with
    every estimator that applies (or is refused by a check across parameters, with one line)."""
    try:
        image = api.render(box, style=style, spp=2, estimator=estimator, **{param: value})
    except StyleError as exc:
        # refused by a check across parameters (u_max must exceed u_min, ...), never by the value's
        # own range
        assert "\n" not in str(exc) and next(
            p for p in style_class(style).params if p.name == param
        ).allowed() not in str(exc), exc
        return
    assert np.isfinite(image).all(), f"{(~np.isfinite(image)).sum()} non-finite values"


def test_the_exp_tone_bound_is_where_float32_stops_resolving():
    """exposure 87 is accepted and renders; just above -ln(FLT_MIN) e^-k would flush to zero in
    float32."""
    assert np.float32(math.exp(-87.0)) >= np.finfo(np.float32).tiny
    assert np.float32(math.exp(-88.0)) < np.finfo(np.float32).tiny
    assert style_class("exp_tone").params[0].high == 87.0


@pytest.mark.skipif(not os.path.exists("/proc/self/maps"), reason="Linux only")
def test_accepted_values_keep_their_meaning_on_the_command_line(tmp_path, capsys):
    """Values inside the ranges still render on the command line, with a finite image."""
    import mitsuba as mi
    out = tmp_path / "ok.exr"
    code = main(
        [
            "render",
            "--style",
            "exp_tone",
            "--set",
            "exposure=87",
            "--max-depth",
            "4294967294",
            "--rr-depth",
            "4294967294",
            "--seed",
            str(2**32 - 1),
            "--width",
            "4",
            "--height",
            "4",
            "--spp",
            "1",
            "-q",
            "-o",
            str(out),
        ]
    )
    assert code == 0, capsys.readouterr().err
    assert np.isfinite(np.array(mi.Bitmap(str(out)))).all()
