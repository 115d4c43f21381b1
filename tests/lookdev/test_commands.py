"""`styletrace render --buffer`, `restyle`, `fit` on the command line."""
import os

import numpy as np
import pytest

from styletrace.frontends import cli
from styletrace.gate import mi
from styletrace.lookdev.buffer import load_buffer
from styletrace.lookdev.restyle import restyle

SMALL = ["--spp", "2", "--inner", "2", "--width", "24", "--height", "16", "-q"]


def read(path):
    return np.array(mi.Bitmap(str(path)), dtype=np.float32)


def test_render_buffer_restyle_fit(tmp_path, capsys):
    buf, img = tmp_path / "b.npz", tmp_path / "r.exr"
    assert cli.main(["render", "--style", "cel", *SMALL, "--buffer", str(buf), "-o", str(img)]) == 0
    b = load_buffer(str(buf))
    np.testing.assert_array_equal(read(img), restyle(b))
    out = tmp_path / "heat.exr"
    assert (
        cli.main(
            ["restyle", str(buf), "--style", "color_map", "--set", "gradient=heat", "-o", str(out)]
        )
        == 0
    )
    np.testing.assert_array_equal(read(out), restyle(b, style="color_map", gradient="heat"))
    fitted = tmp_path / "fit.exr"
    assert (
        cli.main(
            [
                "fit",
                str(buf),
                "--style",
                "contrast",
                "--target",
                str(tmp_path / "t.exr"),
                "-o",
                str(fitted),
            ]
        )
        == 2
    )
    assert "cannot read target image" in capsys.readouterr().err
    target = tmp_path / "t.exr"
    mi.Bitmap(restyle(b, style="contrast", c=2.0, pivot=0.4)).write(str(target))
    assert (
        cli.main(
            ["fit", str(buf), "--style", "contrast", "--target", str(target), "-o", str(fitted)]
        )
        == 0
    )
    printed = capsys.readouterr().out
    import re
    assert "styletrace restyle" in printed
    assert abs(float(re.search(r"--set c=(\S+)", printed).group(1)) - 2.0) < 1e-3
    assert abs(float(re.search(r"--set pivot=(\S+)", printed).group(1)) - 0.4) < 1e-3


def test_one_line_refusals(tmp_path, capsys):
    seq = str(tmp_path / "s.npz")
    assert cli.main(["render", "--style", "gamma", "--estimator", "series", *SMALL, "--buffer", seq,
                     "-o", str(tmp_path / "r.png")]) == 0
    capsys.readouterr()
    assert cli.main(["restyle", seq, "--set", "gamma=1.8", "-o", str(tmp_path / "g.png")]) == 0
    capsys.readouterr()
    assert cli.main(["restyle", seq, "--estimator", "direct", "-o", str(tmp_path / "d.png")]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "estimator 'direct' cannot restyle this buffer" in err
    assert "this estimator needs more" in err
    assert (
        cli.main(
            ["render", *SMALL, "--buffer", str(tmp_path / "b.bin"), "-o", str(tmp_path / "r.png")]
        )
        == 2
    )
    assert "the extension must be .npz" in capsys.readouterr().err
    assert cli.main(["restyle", str(tmp_path / "none.npz"), "-o", str(tmp_path / "x.png")]) == 2
    assert "does not exist" in capsys.readouterr().err


def test_preview_refuses_a_bad_start_in_one_line(capsys):
    assert cli.main(["preview", "--style", "nope", "--width", "8", "--height", "8"]) == 2
    assert "unknown style 'nope'" in capsys.readouterr().err
    assert cli.main(["preview", "--style", "acp", "--width", "8", "--height", "8"]) == 2
    assert "style 'acp' cannot be previewed" in capsys.readouterr().err
    assert cli.main(["preview", "--spp", "100000", "--width", "64", "--height", "64"]) == 2
    assert "over the preview's cap" in capsys.readouterr().err


def test_the_buffer_sizes_in_the_help_are_the_files_written(tmp_path):
    """`--buffer`'s help states what a user sees: at the defaults (denoised) the file holds the
    coverage points, 64 per pixel at 65 bytes, plus the pilot; the help's 128x128 and capped
    figures follow from a small file's measured parts."""
    from styletrace.denoise.coverage import DEFAULT_K
    from styletrace.frontends.lookdev_commands import BUFFER_HELP
    from styletrace.lookdev.buffer import bytes_per_camera_sample
    from styletrace.pipeline.budget import MAX_CAMERA_SAMPLES

    path = tmp_path / "b.npz"
    # --denoise auto as a user has it (the tests' environment sets $STYLETRACE_DENOISE=off)
    assert cli.main(["render", "dragon", "--width", "16", "--height", "16", "-q", "--denoise",
                     "auto", "--buffer", str(path), "-o", str(tmp_path / "b.png")]) == 0
    per = bytes_per_camera_sample("first_hit")
    with np.load(path) as z:
        points = z["pixel"].shape[0]
        pilot = sum(z[k].nbytes for k in z.files if k.startswith("pilot"))
        own = sum(z[k].nbytes for k in z.files if not k.startswith("pilot") and k != "header")
    assert points == 16 * 16 * DEFAULT_K and own == points * per
    assert f"65 bytes each: {DEFAULT_K} per pixel ({DEFAULT_K * per / 1000:.1f} kB a pixel" in \
        BUFFER_HELP and per == 65
    assert f"{(128 * 128 * DEFAULT_K * per + pilot) / 1e6:.1f} MB at 128x128" in BUFFER_HELP
    assert f"{MAX_CAMERA_SAMPLES} points (about " \
        f"{(MAX_CAMERA_SAMPLES * per + pilot) / 1e6:.0f} MB" in BUFFER_HELP
    assert f"pilot's {pilot / 2**20:.1f} MiB" in BUFFER_HELP
    root = os.path.join(os.path.dirname(__file__), "..", "..")
    for name in ("README.md", "docs/lookdev.md", "docs/cli.md"):  # the same figures
        with open(os.path.join(root, name), encoding="utf-8") as f:
            text = " ".join(f.read().split())
        assert f"{(128 * 128 * DEFAULT_K * per + pilot) / 1e6:.1f} MB" in text, name
        assert f"{DEFAULT_K} points per pixel" in text, name
        assert "65 bytes per camera sample" in text, name


@pytest.mark.parametrize("denoise", ["off", "auto"])
def test_the_buffer_header_keeps_a_built_in_scenes_name(denoise, tmp_path):
    """docs/lookdev.md: the header records the scene's name, for a built-in scene its name."""
    path = tmp_path / "b.npz"
    assert cli.main(["render", "furnace", "--width", "8", "--height", "8", "--samples", "4", "-q",
                     "--denoise", denoise, "--buffer", str(path), "-o",
                     str(tmp_path / "b.png")]) == 0
    assert load_buffer(str(path)).header["scene"] == "furnace"
