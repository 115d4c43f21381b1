"""`styletrace render --buffer`, `restyle`, `fit` on the command line."""
import numpy as np

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
