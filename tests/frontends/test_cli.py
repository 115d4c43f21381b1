"""The command line: outputs, determinism, progress, errors and Ctrl-C."""
import os
import re
import signal
import subprocess
import sys
import time

import numpy as np
import pytest
from conftest import child_env

import styletrace
from styletrace.frontends.cli import main
from styletrace.gate import mi
from styletrace.styles import style_class, style_names

ENV = child_env()
SMALL = ["--width", "24", "--height", "16", "--spp", "4", "--inner", "2", "-q"]


def run_cli(*args, timeout=120):
    return subprocess.run(
        [sys.executable, "-m", "styletrace", *args],
        capture_output=True,
        text=True,
        env=ENV,
        timeout=timeout,
    )


def read(path):
    bmp = mi.Bitmap(str(path))
    scale = 255.0 if bmp.component_format() == mi.Struct.Type.UInt8 else 1.0
    return np.array(bmp, dtype=np.float64) / scale


def srgb(x):
    x = np.clip(x, 0, 1)
    return np.where(x <= 0.0031308, 12.92 * x, 1.055 * x ** (1 / 2.4) - 0.055)


def test_styles_lists_every_style_with_parameters(capsys):
    assert main(["styles"]) == 0
    out = capsys.readouterr().out
    for name in style_names():
        assert f"{name}:" in out
        for p in style_class(name).params:
            assert f"    {p.name} = " in out


def test_exr_is_linear_and_png_is_srgb(tmp_path):
    exr, png = tmp_path / "a.exr", tmp_path / "a.png"
    assert main(["render", "--style", "gamma", *SMALL, "--seed", "5", "-o", str(exr)]) == 0
    assert main(["render", "--style", "gamma", *SMALL, "--seed", "5", "-o", str(png)]) == 0
    direct = styletrace.render(
        "cornell-box", style="gamma", spp=4, inner=2, seed=5, width=24, height=16
    )
    linear = read(exr)
    assert linear.shape == (16, 24, 3)
    np.testing.assert_allclose(linear, direct, rtol=1e-6, atol=0)
    encoded = read(png)
    # 8-bit quantization: within one code value of the sRGB encoding of the linear image
    assert np.abs(encoded - srgb(linear)).max() <= 1 / 255 + 1e-6


def test_same_seed_same_image(tmp_path):
    a, b, c = (tmp_path / f"{k}.exr" for k in "abc")
    for path, seed in ((a, 1), (b, 1), (c, 2)):
        assert (
            main(
                [
                    "render",
                    "--style",
                    "cel",
                    *SMALL,
                    "--seed",
                    str(seed),
                    "--pass-spp",
                    "1",
                    "-o",
                    str(path),
                ]
            )
            == 0
        )
    assert np.array_equal(read(a), read(b))
    assert not np.array_equal(read(a), read(c))


def test_sampler_flag_picks_a_builtin_scenes_sample_pattern(tmp_path):
    out = {k: tmp_path / f"{k}.exr" for k in ("independent", "owen_sobol", "default")}
    for name, path in out.items():
        flag = [] if name == "default" else ["--sampler", name]
        assert main(["render", "--style", "identity", *SMALL, "--denoise", "off", *flag,
                     "-o", str(path)]) == 0
    independent = styletrace.render("cornell-box", style="identity", spp=4, inner=2,
                                    width=24, height=16, denoise="off", sampler="independent")
    np.testing.assert_allclose(read(out["independent"]), independent, rtol=1e-6, atol=0)
    assert np.array_equal(read(out["owen_sobol"]), read(out["default"]))
    assert not np.array_equal(read(out["independent"]), read(out["default"]))


def test_progress_bar_for_multi_pass_renders(tmp_path):
    r = run_cli(
        "render",
        "--width",
        "24",
        "--height",
        "16",
        "--spp",
        "4",
        "--inner",
        "2",
        "--pass-spp",
        "1",
        "-o",
        str(tmp_path / "p.png"),
    )
    assert r.returncode == 0, r.stderr
    assert "4/4" in r.stderr and "spp" in r.stderr


BAD = [
    (["--style", "nope"], "unknown style 'nope'"),
    (["--style", "cel", "--set", "foo=1"], "unknown property 'foo'"),
    (["--style", "cel", "--set", "thresholds=abc"], "bad value 'abc' for parameter 'thresholds'"),
    (["--style", "gamma", "--set", "gamma=-1"], "bad value '-1' for parameter 'gamma'"),
    (["--style", "cel", "--set", "levels"], "bad --set 'levels'"),
    (["--inner", "0"], "bad value '0' for --inner:"),
    (["--spp", "0"], "bad value 0 for --spp"),
    (["--stylize", "everywhere"], "bad value 'everywhere' for --stylize:"),
    (["--estimator", "magic"], "unknown estimator 'magic'"),
    (["no-such-scene"], "unknown scene 'no-such-scene'"),
    (["missing.xml"], "scene file 'missing.xml' does not exist"),
    (["-o", "/no/such/folder/x.png"], "folder '/no/such/folder' does not exist"),
    (["-o", "out.jpg"], "bad output 'out.jpg'"),
    (["--lines", "--set", "line_width=-2"], "bad value '-2' for 'line_width'"),
    (["--lines", "--set", "lines=maybe"], "bad value 'maybe' for 'lines'"),
    (["--lines", "--set", "line_tests=outline"], "bad value 'outline' in 'line_tests'"),
    (
        ["--style", "gamma", "--estimator", "series", "--expansion-pass", "-1"],
        "bad value -1 for --expansion-pass",
    ),
    (
        ["--style", "gamma", "--expansion-pass", "8"],
        "bad value 8 for --expansion-pass with estimator 'direct'",
    ),
]


@pytest.mark.parametrize("args,message", BAD, ids=[m for _, m in BAD])
def test_bad_input_one_line_and_exit_2(args, message, capsys, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    assert main(["render", "-q", *args]) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith("styletrace: error: ") and message in err
    assert "\n" not in err


@pytest.mark.parametrize("text,message", [
    ('<scene version="3.0.0"><shape type="sphere">', "Parsing of XML file"),
    ('<scene version="3.0.0"><shape type="spheer"/></scene>', 'Plugin "spheer" not found'),
])
def test_broken_xml_one_line_and_exit_2(text, message, tmp_path):
    path = tmp_path / "scene.xml"
    path.write_text(text)
    r = run_cli("render", str(path), "-o", str(tmp_path / "x.png"))
    assert r.returncode == 2
    lines = r.stderr.strip().splitlines()
    assert len(lines) == 1 and message in lines[0], r.stderr


def test_unwritable_output_fails_before_rendering(tmp_path):
    target = tmp_path / "x.png"
    target.mkdir()
    r = run_cli("render", "-q", "-o", str(target))
    assert r.returncode == 2 and "it is a folder" in r.stderr
    folder = tmp_path / "ro"
    folder.mkdir()
    folder.chmod(0o500)
    if not os.access(folder, os.W_OK):  # root ignores permission bits; the check above covers it
        r = run_cli("render", "-q", "-o", str(folder / "x.png"))
        assert r.returncode == 2 and "permission denied" in r.stderr


def test_xml_scene_with_stylized_integrator(tmp_path):
    path = tmp_path / "s.xml"
    path.write_text("""<scene version="3.0.0">
      <default name="resx" value="20"/><default name="resy" value="12"/>
      <integrator type="stylized"><string name="style" value="cel"/><string name="levels" \
value="0.2,0.9"/>
        <string name="thresholds" value="0.75"/><integer name="inner_samples" \
value="2"/></integrator>
      <sensor type="perspective"><transform name="to_world"><lookat origin="0,0,4" target="0,0,0" \
up="0,1,0"/></transform>
        <film type="hdrfilm"><integer name="width" value="$resx"/><integer name="height" \
value="$resy"/>
        <rfilter type="box"/></film></sensor>
      <shape type="sphere"><bsdf type="diffuse"/></shape><emitter type="constant"/></scene>""")
    out = tmp_path / "o.exr"
    r = run_cli("render", str(path), "--width", "10", "--spp", "2", "-o", str(out))
    assert r.returncode == 0, r.stderr
    img = read(out)
    assert img.shape == (12, 10, 3)
    assert "levels=0.2,0.9" in r.stderr
    # the sphere (albedo 0.5 under a white sky: brightness 0.5 < 0.75) is cel-shaded to exactly 0.2;
    # the sky, seen directly, stays unstylized at 1
    u = img.mean(axis=2)
    np.testing.assert_allclose(u[5:7, 4:6], 0.2, atol=1e-5)
    np.testing.assert_allclose(u[0, 0], 1.0, atol=1e-5)


def test_sampler_flag_with_a_scene_file_is_one_line_and_exit_2(tmp_path, capsys):
    path = tmp_path / "s.xml"
    path.write_text('<scene version="3.0.0"><shape type="sphere"/></scene>')
    assert main(["render", "-q", str(path), "--sampler", "independent",
                 "-o", str(tmp_path / "o.exr")]) == 2
    err = capsys.readouterr().err.strip()
    assert "bad sampler choice 'independent'" in err and "built-in scenes only" in err
    assert "\n" not in err and not (tmp_path / "o.exr").exists()
    with pytest.raises(SystemExit) as stop:
        main(["render", "-q", "--sampler", "halton"])
    assert stop.value.code == 2
    assert "--sampler: invalid choice: 'halton'" in capsys.readouterr().err


def interrupt(out, pass_spp, ctrl_c, sig=signal.SIGINT):
    """Start a long render, wait until tqdm reports `pass_spp * 2` (resp. one pass) done, send `sig`
    (Ctrl-C: SIGINT) `ctrl_c` times, and return (exit status, stderr after the signal)."""
    proc = subprocess.Popen(
        [
            sys.executable,
            "-m",
            "styletrace",
            "render",
            "--width",
            "64",
            "--height",
            "64",
            "--spp",
            "100000",
            "--inner",
            "4",
            "--pass-spp",
            str(pass_spp),
            "-o",
            str(out),
        ],
        stderr=subprocess.PIPE,
        env=ENV,
    )
    wait_for = f"{2 * pass_spp if pass_spp == 1 else pass_spp}/100000".encode()
    seen = b""
    deadline = time.time() + 120
    while wait_for not in seen and time.time() < deadline:
        seen += os.read(proc.stderr.fileno(), 4096)
    for i in range(ctrl_c):
        if i:
            time.sleep(0.3)
        proc.send_signal(sig)
    rest = proc.communicate(timeout=120)[1]
    return proc.returncode, seen + rest, rest


def test_ctrl_c_writes_the_finished_passes(tmp_path):
    out = tmp_path / "partial.exr"
    code, log, rest = interrupt(out, 1, 1)
    assert code == 130, log.decode()
    assert b"interrupted; wrote" in rest
    img = read(out)
    assert img.shape == (64, 64, 3) and np.isfinite(img).all() and img.mean() > 0


def test_second_ctrl_c_abandons_the_pass_under_way(tmp_path):
    out = tmp_path / "partial.exr"
    code, log, rest = interrupt(out, 400, 2)
    assert code == 130, log.decode()
    assert b"wrote" in rest and b"of 100000 spp" in rest
    assert read(out).shape == (64, 64, 3)


def test_sigterm_is_like_ctrl_c_with_status_143(tmp_path):
    out = tmp_path / "partial.exr"
    code, log, rest = interrupt(out, 1, 1, signal.SIGTERM)
    assert code == 143, log.decode()
    assert b"SIGTERM" in rest and b"interrupted; wrote" in rest
    img = read(out)
    assert img.shape == (64, 64, 3) and np.isfinite(img).all() and img.mean() > 0


def started(args: list, marker: bytes):
    """`styletrace ARGS` started with its stderr read until `marker` shows (the render's progress
    line); (the process, what it printed so far). A process that ends first fails the test with
    what it printed."""
    proc = subprocess.Popen(
        [sys.executable, "-m", "styletrace", *args], stderr=subprocess.PIPE, env=ENV
    )
    seen = b""
    while marker not in seen:
        chunk = os.read(proc.stderr.fileno(), 4096)
        assert chunk, seen.decode()
        seen += chunk
    return proc, seen


@pytest.mark.parametrize("sig,status", [(signal.SIGINT, 130), (signal.SIGTERM, 143)])
def test_one_signal_stops_a_long_pass(tmp_path, sig, status):
    """A pass of 2^20 camera samples with 64 inner samples each runs for minutes on a CPU; one
    signal ends the render after the grace period, not after the pass (the first pass: nothing to
    write)."""
    out = tmp_path / "never.exr"
    proc, seen = started(
        [
            "render",
            "--width",
            "64",
            "--height",
            "64",
            "--spp",
            "512",
            "--inner",
            "64",
            "--pass-spp",
            "256",
            "-o",
            str(out),
        ],
        b"0/512",
    )
    time.sleep(0.5)
    proc.send_signal(sig)
    rest = proc.communicate(timeout=90)[1]
    assert proc.returncode == status, (seen + rest).decode()
    assert b"nothing written" in rest and not out.exists()


#: a pass of 64 x 64 camera samples with 4000 inner samples each: about 4 s on an idle 2-core
#: machine, so a signal 0.5 s after the first pass finished lands in the second pass's kernel
#: (Mitsuba traces a pass in 10-30 ms, and a SIGINT in that window is Mitsuba's: `StopSignals`), and
#: the pass is still running 1 s after a second one 0.2 s later
LONG_PASSES = [
    "render",
    "--width",
    "64",
    "--height",
    "64",
    "--spp",
    "1000",
    "--inner",
    "4000",
    "--pass-spp",
    "1",
    "--seed",
    "7",
]


@pytest.fixture(scope="module")
def one_long_pass(tmp_path_factory):
    """The first pass of LONG_PASSES on its own: what an interrupted render must have written."""
    out = tmp_path_factory.mktemp("reference") / "one.exr"
    r = run_cli(*LONG_PASSES[:5], "--spp", "1", *LONG_PASSES[7:], "-q", "-o", str(out), timeout=300)
    assert r.returncode == 0, r.stderr
    return read(out)


@pytest.mark.parametrize("sig,count,status", [
    (signal.SIGINT, 2, 130),  # a second signal: at once
    (signal.SIGTERM, 1, 143),  # one signal: after the grace period, the same write
])
def test_a_signal_in_a_long_pass_writes_the_finished_pass(
    tmp_path, one_long_pass, sig, count, status
):
    """The pass under way is abandoned, not waited for: the image is the first pass, bit for bit
    (the same seed gives the same passes), with the exit status of the signal. When the watcher
    abandons (a second signal, or the grace period over) is `StopSignals`' own, tested without a
    clock in tests/pipeline/test_signals.py; before the watcher's write went around Mitsuba
    (images.encode_plain) it waited for the pass's kernel (6.3 to 15.8 s measured)."""
    out = tmp_path / "partial.exr"
    proc, seen = started([*LONG_PASSES, "-o", str(out)], b"1/1000")
    time.sleep(0.5)  # into the second pass's kernel (LONG_PASSES)
    for i in range(count):
        if i:
            time.sleep(0.2)
        proc.send_signal(sig)
    rest = proc.communicate(timeout=120)[1]
    assert proc.returncode == status, (seen + rest).decode()
    assert b"interrupted; wrote" in rest and b"from 1 of 1000 spp" in rest, rest.decode()
    np.testing.assert_array_equal(read(out), one_long_pass)


def test_non_finite_pixels_are_counted_in_one_line(tmp_path, capsys, monkeypatch):
    from styletrace.frontends import api

    def nan_passes(shot, *a, **kw):
        spp = shot.spp
        layout = api.tiles(3, 2)
        total = np.ones((2, 3, 3), np.float32)
        total[0, 0, 1], total[1, 2, :] = np.nan, np.inf
        yield api.Progress(spp, total * spp, np.array([spp]), layout)

    from styletrace.pipeline import execute
    monkeypatch.setattr(execute, "run_passes", nan_passes)  # the pass loop the CLI's executor runs
    out = tmp_path / "n.png"
    assert main(["render", *SMALL, "-o", str(out)]) == 0
    err = capsys.readouterr().err
    assert (
        "styletrace: warning: 2 pixel(s) are not finite (NaN or inf): NaN as 0 and +inf as 1 in "
        "the PNG" in err
    )
    assert (read(out)[..., 0] == [[1, 1, 1], [1, 1, 1]]).all() and read(out)[0, 0, 1] == 0


def test_output_that_is_the_scene_is_refused_before_loading(tmp_path, capsys):
    scene = tmp_path / "s.xml"
    scene.write_text(GAMMA_XML)
    before = scene.read_bytes()
    (tmp_path / "s.exr").symlink_to(scene)
    assert main(["render", str(scene), "-o", str(tmp_path / "s.exr")]) == 2
    assert "it is the scene file being rendered" in capsys.readouterr().err
    assert scene.read_bytes() == before


GAMMA_XML = """<scene version="3.0.0">
  <integrator type="stylized"><string name="style" value="gamma"/><float name="gamma" value="4"/>
    <float name="exposure" value="1"/><integer name="inner_samples" value="2"/></integrator>
  <sensor type="perspective"><transform name="to_world"><lookat origin="0,0,4" target="0,0,0" \
up="0,1,0"/></transform>
    <film type="hdrfilm"><integer name="width" value="8"/><integer name="height" \
value="8"/><rfilter type="box"/></film></sensor>
  <shape type="sphere"><bsdf type="diffuse"/></shape><emitter type="constant"/></scene>"""


def test_flags_refine_the_scenes_own_integrator(tmp_path, capsys):
    path = tmp_path / "g.xml"
    path.write_text(GAMMA_XML)
    out = tmp_path / "o.exr"
    assert main(["render", str(path), "--inner", "4", "--spp", "1", "-o", str(out)]) == 0
    # --inner alone keeps the scene's style
    assert "gamma(gamma=4, exposure=1)" in capsys.readouterr().err
    # the sphere (albedo 0.5 under a white sky) is 0.5^(1/4) with gamma 4; --max-depth 1 leaves
    # emission only
    np.testing.assert_allclose(read(out)[3:5, 3:5], 0.5 ** 0.25, rtol=0.05)
    assert main(["render", str(path), "--max-depth", "1", "--spp", "1", "-q", "-o", str(out)]) == 0
    np.testing.assert_allclose(read(out)[3:5, 3:5], 0.0, atol=1e-6)
    assert main(["render", str(path), "--style", "cel", "--spp", "1", "-o", str(out)]) == 0
    err = capsys.readouterr().err
    # a new style drops the old one's parameters: cel at its own defaults (auto thresholds and
    # levels, printed)
    assert re.search(r"styletrace: auto values: cel thresholds=[0-9.,]+ levels=[0-9.,]+", err), err
    assert "bands=3" in err and "gamma=" not in err


@pytest.mark.parametrize("style", ["contrast", "exp_tone", "reinhard", "gamma", "tie_dye"])
def test_the_tone_styles_auto_exposure_is_printed_and_a_given_one_wins(style, tmp_path, capsys):
    out = tmp_path / "o.exr"
    assert (
        main(
            [
                "render",
                "--style",
                style,
                "--width",
                "8",
                "--height",
                "8",
                "--spp",
                "1",
                "--inner",
                "1",
                "-o",
                str(out),
            ]
        )
        == 0
    )
    err = capsys.readouterr().err
    assert f"styletrace: auto values: {style} exposure=" in err, err
    assert (
        main(
            [
                "render",
                "--style",
                style,
                "--set",
                "exposure=2",
                "--width",
                "8",
                "--height",
                "8",
                "--spp",
                "1",
                "--inner",
                "1",
                "-o",
                str(out),
            ]
        )
        == 0
    )
    err = capsys.readouterr().err
    assert "auto values" not in err and "exposure=2" in err, err


@pytest.mark.parametrize("args", [["--spp", "abc"], ["--no-such-flag"], []])
def test_malformed_arguments_are_one_line(args, capsys):
    with pytest.raises(SystemExit) as exc:
        main(["render", *args] if args else [])
    assert exc.value.code == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith("styletrace: error: ") and "\n" not in err


def test_a_failing_later_pass_keeps_the_finished_ones(tmp_path, capsys, monkeypatch):
    from styletrace.pipeline import execute
    real = execute.run_passes

    def failing(*a, **k):
        gen = real(*a, **k)
        yield next(gen)
        raise RuntimeError("jit_malloc(): out of memory\nsecond line")

    monkeypatch.setattr(execute, "run_passes", failing)  # the pass loop the CLI's executor runs
    out = tmp_path / "p.exr"
    assert main(["render", *SMALL, "--pass-spp", "1", "-o", str(out)]) == 1
    err = capsys.readouterr().err.strip()
    assert (
        "\n" not in err
        and "error after 1 of 4 spp (second line)" in err
        and "wrote the finished passes" in err
    )
    assert read(out).shape == (16, 24, 3)


def test_lines_flag_and_set_draw_lines(tmp_path, capsys):
    """`--lines` alone turns lines on; `--set line_color=...` reaches them; `styletrace lines`
    lists the settings."""
    args = ["render", "--style", "identity", "--width", "24", "--height", "24", "--spp", "2", "-q"]
    assert main([*args, "furnace", "-o", str(tmp_path / "plain.exr")]) == 0
    assert main([*args, "--lines", "furnace", "--set", "line_color=0,9,0", "--set", "line_width=3",
                 "-o", str(tmp_path / "lines.exr")]) == 0
    plain, lines = read(tmp_path / "plain.exr"), read(tmp_path / "lines.exr")
    green = lines[..., 1] > 5   # the furnace's radiance is at most 1: only a line is this green
    assert green.sum() > 20 and not (plain[..., 1] > 5).any()
    assert main(["lines"]) == 0
    out = capsys.readouterr().out
    assert "line_width = 2.0" in out and "line_samples" in out and "docs/lines.md" in out


def test_wild_series_estimates_are_reported_after_the_render(tmp_path, capsys):
    """One warning line on stderr, after the image is written (styletrace.wild); none for direct."""
    out = tmp_path / "g.exr"
    common = [
        "render",
        "--style",
        "gamma",
        "--width",
        "32",
        "--height",
        "32",
        "--spp",
        "4",
        "--inner",
        "16",
        "--seed",
        "0",
        "-q",
        "-o",
        str(out),
    ]
    assert main([*common, "--estimator", "series"]) == 0
    lines = [ln for ln in capsys.readouterr().err.splitlines() if "are wild" in ln]
    assert (
        out.exists()
        and len(lines) == 1
        and lines[0].startswith("styletrace: warning: the 'series' estimator")
    )
    assert "use --expansion-pass 64 or --estimator direct" in lines[0]
    assert main([*common, "--estimator", "direct"]) == 0
    assert "are wild" not in capsys.readouterr().err


def test_expansion_pass_flag_and_set(tmp_path):
    """`--expansion-pass M` and `--set expansion_pass=M` run the pass: the same image, other than
    without it; its values stay near g's range where the renderer's series alone gives -23.6
    (test_wild_estimates)."""
    common = [
        "render",
        "--style",
        "gamma",
        "--estimator",
        "series",
        "--width",
        "32",
        "--height",
        "32",
        "--spp",
        "4",
        "--inner",
        "16",
        "--seed",
        "0",
        "-q",
    ]
    imgs = []
    for extra in (["--expansion-pass", "64"], ["--set", "expansion_pass=64"], []):
        out = tmp_path / f"e{len(imgs)}.exr"
        assert main([*common, *extra, "-o", str(out)]) == 0
        imgs.append(read(out))
    assert np.array_equal(imgs[0], imgs[1]) and not np.array_equal(imgs[0], imgs[2])
    assert imgs[0].min() > -1.0 and imgs[2].min() < -10.0


# ---- no silent waits: a long phase names itself on stderr (status.py) ----------------------------
def test_long_phases_name_themselves_on_stderr(tmp_path):
    """With STYLETRACE_STATUS_DELAY=0 every phase is long enough to show: the load, the auto
    values' pilot and the first pass (its kernel compilation included); -q shows none of it."""
    env = dict(ENV, STYLETRACE_STATUS_DELAY="0")
    args = [
        "render",
        "--style",
        "cel",
        "--width",
        "16",
        "--height",
        "16",
        "--spp",
        "2",
        "--inner",
        "1",
        "-o",
        str(tmp_path / "s.png"),
    ]
    one = subprocess.run(
        [sys.executable, "-m", "styletrace", *args],
        capture_output=True,
        text=True,
        env=env,
        timeout=120,
    )
    assert one.returncode == 0, one.stderr
    for words in ("styletrace: loading scene cornell-box (", "compiling and rendering a pilot (",
                  "styletrace: compiling and rendering ("):
        assert words in one.stderr, one.stderr
    two = subprocess.run(
        [sys.executable, "-m", "styletrace", *args, "--pass-spp", "1"],
        capture_output=True,
        text=True,
        env=env,
        timeout=120,
    )
    assert two.returncode == 0, two.stderr
    assert (
        "compiling and rendering pass 1 of 2" in two.stderr and "rendering: 100%" in two.stderr
    ), two.stderr
    quiet = subprocess.run(
        [sys.executable, "-m", "styletrace", *args, "--pass-spp", "1", "-q"],
        capture_output=True,
        text=True,
        env=env,
        timeout=120,
    )
    assert quiet.returncode == 0 and quiet.stderr == "", quiet.stderr


def test_a_slow_first_pass_is_named_at_the_default_delay(tmp_path):
    """At the default delay (2 s) a single pass of 64 x 64 x 4096 paths (about 5 s on 2 cores)
    shows its line; the pilot is skipped (thresholds given) and the load is quick, so they stay
    quiet."""
    r = run_cli(
        "render",
        "--style",
        "cel",
        "--set",
        "thresholds=0.3",
        "--width",
        "64",
        "--height",
        "64",
        "--spp",
        "1",
        "--inner",
        "4096",
        "-o",
        str(tmp_path / "slow.png"),
    )
    assert r.returncode == 0, r.stderr
    assert "styletrace: compiling and rendering (" in r.stderr, r.stderr
    assert "loading scene" not in r.stderr and "pilot" not in r.stderr, r.stderr


def test_status_shows_only_phases_longer_than_its_delay():
    import io

    from styletrace.errors import UsageError
    from styletrace.frontends.status import Status, delay_from_env
    out = io.StringIO()
    status = Status(delay=0.3, stream=out)
    with status.phase("quick"):
        pass
    with status.phase("slow thing"):
        time.sleep(1.2)
    assert "quick" not in out.getvalue()
    assert "styletrace: slow thing (1 s)" in out.getvalue() and out.getvalue().endswith("\n"), repr(
        out.getvalue()
    )
    silent = io.StringIO()
    with Status(enabled=False, delay=0.0, stream=silent).phase("anything"):
        time.sleep(0.3)
    assert silent.getvalue() == ""
    os.environ["STYLETRACE_STATUS_DELAY"] = "soon"
    try:
        with pytest.raises(UsageError, match="bad value 'soon' for STYLETRACE_STATUS_DELAY"):
            delay_from_env()
    finally:
        del os.environ["STYLETRACE_STATUS_DELAY"]


DOCS = os.path.join(os.path.dirname(__file__), "..", "..", "docs")


def doc(name):
    with open(os.path.join(DOCS, name), encoding="utf-8") as f:
        return f.read()


def render_parser():
    from styletrace.frontends.cli import build_parser
    return build_parser()._subparsers._group_actions[0].choices["render"]


def test_render_help_lists_every_built_in_scene(capsys):
    """From the one registry (`scene.builtin.BUILTIN`): `lines` was missing from a hand-written
    list."""
    from styletrace.scene.builtin import BUILTIN, DEFAULT
    scene = next(a for a in render_parser()._actions if a.dest == "scene")
    listed = scene.help.split("(", 1)[1].split(")", 1)[0].split(", ")
    assert listed[0] == DEFAULT and sorted(listed) == sorted(BUILTIN)


@pytest.mark.skipif(not os.path.isdir("/sys"), reason="needs Linux's /sys")
@pytest.mark.parametrize("flag,name", [("-o", "out.png"), ("--buffer", "b.npz")])
def test_an_output_folder_that_refuses_files_fails_before_rendering(flag, name, tmp_path, capsys):
    """/sys looks writable to root but refuses new files: one line, exit 2, nothing rendered (no
    auto values, no summary), where it once rendered and then failed with three lines and exit
    1."""
    out = ["-o", str(tmp_path / "x.png")] if flag == "--buffer" else []
    assert main(["render", "--width", "8", "--height", "8", "--samples", "4", *out, flag,
                 f"/sys/{name}"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and err.startswith(f"styletrace: error: cannot write '/sys/{name}'")
    assert not os.listdir(tmp_path)


@pytest.mark.skipif(not os.path.isdir("/sys"), reason="needs Linux's /sys")
@pytest.mark.parametrize("argv", [["gallery", "--quick", "-o", "/sys"],
                                  ["restyle", "BUFFER", "-o", "/sys/r.png"]])
def test_other_outputs_in_a_folder_that_refuses_files_fail_first(argv, tmp_path, capsys):
    buffer = tmp_path / "b.npz"
    assert main(["render", "-q", *SMALL, "--denoise", "off", "--buffer", str(buffer), "-o",
                 str(tmp_path / "b.png")]) == 0
    assert main([str(buffer) if a == "BUFFER" else a for a in argv]) == 2
    err = capsys.readouterr().err
    # root: the folder refuses the attempt; anyone else: its permission bits already do
    assert err.count("\n") == 1 and err.startswith("styletrace: error: cannot write") \
        and "'/sys" in err, err


def option_lines():
    """docs/cli.md's list of every option: {option string: its line}."""
    text = doc("cli.md").split("### Every option, with its default", 1)[1].split("\n## ", 1)[0]
    out = {}
    for line in text.splitlines():
        if line.startswith("- `"):
            head = line.split(":", 1)[0]
            for name in re.findall(r"`(-{1,2}[\w-]+|SCENE)", head):
                out[name] = line
    return out


def test_docs_cli_lists_every_render_option_with_its_default():
    """docs/cli.md calls itself the full reference: every option of `render --help` has its line
    there, with the default the parser or the settings table gives it, and no line names an option
    that does not exist."""
    from styletrace.config import settings
    lines = option_lines()
    props = {p.flag: p for p in settings.PROPERTIES if p.flag}
    parser = render_parser()
    options = set()
    for action in parser._actions:
        if action.dest == "help":
            continue
        names = action.option_strings or ["SCENE"]
        options.update(names)
        for name in names:
            assert name in lines, f"{name} is missing from docs/cli.md's list of every option"
        line = lines[names[-1]].lower()
        if action.nargs == 0:  # a switch
            assert "default off" in line, line
        elif names[-1] in props and names[-1] != "--style":
            assert f"default `{props[names[-1]].show_default().lower()}`" in line, line
        elif action.default not in (None, [], False):
            assert f"default `{action.default}`" in line, line
    assert set(lines) <= options, set(lines) - options
    assert "default: the scene's own `stylized` integrator's, else " \
        f"`{settings.COMMAND_LINE_STYLE}`" in lines["--style"]


def test_the_denoise_uncertainty_default_is_the_same_everywhere():
    from styletrace.denoise.expectation import UNCERTAINTY
    action = next(a for a in render_parser()._actions if a.dest == "denoise_uncertainty")
    assert f"(default {UNCERTAINTY:g}:" in action.help
    assert f"`--denoise-uncertainty U`: g averaged over the denoised expectation's residual " \
        f"error; default `{UNCERTAINTY:g}`" in doc("cli.md")
    assert f"default {UNCERTAINTY:g}, which styles D itself" in doc("denoise.md")


FLAG_ERRORS = [
    (["--inner", "0"], "bad value '0' for --inner: expected an integer in [1, "),
    (["--spp", "0"], "bad value 0 for --spp: expected an integer >= 1"),
    (["--samples", "0"], "bad value 0 for --samples: expected an integer >= 1"),
    (["--max-depth", "-5"], "bad value -5 for --max-depth: expected an integer in [-1, "),
    (["--seed", "-1"], "bad value -1 for --seed: expected an integer in [0, 4294967295]"),
    (["--stylize-depth", "0"], "bad value 0 for --stylize-depth: expected an integer in [1, 16]"),
    (["--rr-depth", "0"], "bad value 0 for --rr-depth: expected an integer in [1, "),
    (["--reuse", "pixels", "--stylize", "first_object_hit", "--style", "identity"],
     "for --stylize: --reuse pixels pools samples at the first hit"),
    # typed as a property with --set: named as typed
    (["--set", "inner_samples=0"], "bad value '0' for 'inner_samples': expected"),
    (["--inner", "4", "--set", "inner_samples=0"], "bad value '0' for 'inner_samples': expected"),
    (["--set", "max_depth=-5"], "bad value '-5' for 'max_depth': expected"),
]


@pytest.mark.parametrize("args,message", FLAG_ERRORS, ids=[" ".join(a) for a, _ in FLAG_ERRORS])
def test_errors_name_the_flag_the_user_typed(args, message, capsys, tmp_path):
    assert main(["render", "-q", "--width", "8", "--height", "8", *args, "-o",
                 str(tmp_path / "x.png")]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and message in err, err


def test_python_errors_keep_the_property_names():
    from styletrace.errors import SettingsError
    with pytest.raises(SettingsError, match="bad value 0 for 'inner_samples'"):
        styletrace.render("furnace", width=8, height=8, inner=0)
    with pytest.raises(SettingsError, match="bad value -5 for 'max_depth'"):
        styletrace.render("furnace", width=8, height=8, max_depth=-5)


def test_flag_terms_translate_only_the_typed_flags():
    from styletrace.frontends.cli import in_flag_terms
    flags = {"inner_samples": "--inner", "aovs": "--aovs", "reuse": "--reuse"}
    assert in_flag_terms("bad value 1 for spp with aovs=True: x; use reuse=off or "
                         "stylize=first_hit; for 'inner_samples' and 'max_depth'", flags) == (
        "bad value 1 for spp with --aovs: x; use --reuse off or stylize=first_hit; for --inner "
        "and 'max_depth'")


def auto_line(args, capsys, tmp_path):
    assert main(["render", "--width", "32", "--height", "32", "--denoise", "auto", *args, "-o",
                 str(tmp_path / "a.png")]) == 0
    return next(line for line in capsys.readouterr().err.splitlines()
                if line.startswith("styletrace: auto values: "))


def test_the_auto_values_line_in_the_docs_is_the_one_printed(capsys, tmp_path):
    """docs/cli.md, styles.md and look.md show the line `styletrace render --style cel` prints on
    the Cornell box (whose auto values do not depend on a square film's size)."""
    line = auto_line(["--style", "cel"], capsys, tmp_path)
    for name in ("cli.md", "styles.md", "look.md"):
        assert line in doc(name), name


def test_the_cel_example_shows_three_bands_on_the_cornell_box(tmp_path):
    """docs/cli.md's cel example: every band holds a real share of the image (once 99% fell in the
    darkest); the shares it states, within 3%."""
    example = next(line.split() for line in doc("cli.md").splitlines()
                   if line.strip().startswith("styletrace render --style cel --set thresholds="))
    args = example[2:example.index("-o")]
    out = tmp_path / "cel.exr"
    assert main(["render", *args, "--width", "64", "--height", "64", "-q", "--denoise", "auto",
                 "-o", str(out)]) == 0
    levels = np.array([float(v) for v in args[args.index("--set", 4) + 1].split("=")[1].split(",")])
    u = read(out).mean(axis=2)
    band = np.argmin(np.abs(u[..., None] - levels), axis=2)[u > 0.01]  # the box's black frame out
    shares = [float((band == j).sum()) / u.size for j in range(len(levels))]
    assert np.allclose(shares, [0.29, 0.38, 0.28], atol=0.03), shares


def test_frames_render_here_denoised_as_a_still(tmp_path, capsys):
    """Without --ray a turntable's frames render in this process, each denoised as a still is:
    frame 0 (the scene's own camera) is the denoised still bit for bit, and frame 1 differs from
    the same frame with --denoise off (the denoiser ran on the moved camera too)."""
    common = ["render", "--style", "cel", "--width", "24", "--height", "24", "-q"]
    # (the suite's environment makes --denoise default to off: tests/conftest.py)
    assert main([*common, "--frames", "2", "--orbit", "30", "--denoise", "auto",
                 "-o", str(tmp_path / "on.exr")]) == 0
    assert main([*common, "--frames", "2", "--orbit", "30", "--denoise", "off",
                 "-o", str(tmp_path / "off.exr")]) == 0
    assert main([*common, "--denoise", "auto", "-o", str(tmp_path / "still.exr")]) == 0
    on = [read(tmp_path / f"on_{k:04d}.exr") for k in range(2)]
    off = [read(tmp_path / f"off_{k:04d}.exr") for k in range(2)]
    assert np.array_equal(on[0], read(tmp_path / "still.exr"))
    assert not np.array_equal(on[1], off[1]) and not np.array_equal(on[0], on[1])
    manifest = (tmp_path / "on.exr.frames.json").read_text()
    assert '"denoise": "auto"' in manifest and '"done": [\n  0,\n  1\n ]' in manifest


def test_frames_with_temporal_reuse_off_are_each_the_still(tmp_path, capsys):
    """`--orbit 0`: every frame on the still's camera. With `--temporal-reuse off` every frame is
    the denoised still bit for bit (the same seed, no history: the frames before reuse); with it
    on (the default) frame 0 is still the still (no history yet) and the frames after it differ
    (their own seeds, blended). The manifest names reuse and chunk only where reuse applies, so
    a resume with other ones is refused in one line."""
    common = ["render", "--style", "cel", "--width", "16", "--height", "16", "--samples", "4",
              "--denoise", "auto", "-q"]
    assert main([*common, "--frames", "3", "--orbit", "0", "--temporal-reuse", "off",
                 "-o", str(tmp_path / "off.exr")]) == 0
    assert main([*common, "--frames", "3", "--orbit", "0", "--chunk", "2",
                 "-o", str(tmp_path / "on.exr")]) == 0
    assert main([*common, "-o", str(tmp_path / "still.exr")]) == 0
    still = read(tmp_path / "still.exr")
    off = [read(tmp_path / f"off_{k:04d}.exr") for k in range(3)]
    on = [read(tmp_path / f"on_{k:04d}.exr") for k in range(3)]
    assert all(np.array_equal(f, still) for f in off)
    assert np.array_equal(on[0], still) and not np.array_equal(on[1], still)
    assert not np.array_equal(on[1], on[2])
    assert '"chunk"' not in (tmp_path / "off.exr.frames.json").read_text()
    assert '"chunk": 2' in (tmp_path / "on.exr.frames.json").read_text()
    capsys.readouterr()
    assert main([*common, "--frames", "3", "--orbit", "0", "--resume",
                 "-o", str(tmp_path / "on.exr")]) == 2
    err = capsys.readouterr().err.strip()
    assert "cannot resume" in err and "other settings" in err and err.count("\n") == 0
    assert main([*common, "--frames", "3", "--chunk", "0", "-o", str(tmp_path / "x.exr")]) == 2
    err = capsys.readouterr().err.strip()
    assert "bad value 0 for --chunk" in err and err.count("\n") == 0
