"""The error AOVs at the front ends: `--aovs` into a multi-channel EXR, `aovs=True` in Python,
refusals."""
import numpy as np
import pytest

import styletrace
from styletrace.errors import UsageError
from styletrace.frontends import api
from styletrace.frontends.cli import main
from styletrace.gate import mi
from styletrace.images import AOV_CHANNELS

styletrace.init()
SMALL = ["--width", "16", "--height", "12", "--spp", "2", "-q"]


def channels(path):
    bmp = mi.Bitmap(str(path))
    names = [bmp.struct_()[i].name for i in range(bmp.channel_count())]
    return dict(zip(names, np.moveaxis(np.array(bmp), -1, 0)))


def test_the_exr_carries_named_aov_channels(tmp_path):
    out = tmp_path / "a.exr"
    assert main(["render", "cornell-box", *SMALL, "--inner", "3", "--aovs", "-o", str(out)]) == 0
    ch = channels(out)
    want = {"R", "G", "B"} | {c for _, names in AOV_CHANNELS for c in names}
    assert set(ch) == want
    # each camera sample used 3 children, or none where it left the box (the wide film sees past its
    # walls)
    assert set(np.unique(ch["children"])) <= {0.0, 1.5, 3.0} and np.mean(ch["children"] == 3) > 0.5
    assert np.all(np.isfinite(ch["variance.R"])) and np.all(ch["variance.R"] >= 0)
    # the image channels are the render's without --aovs (same seed and split)
    plain = tmp_path / "b.exr"
    assert main(["render", "cornell-box", *SMALL, "--inner", "3", "-o", str(plain)]) == 0
    assert np.array_equal(
        np.array(mi.Bitmap(str(plain))), np.stack([ch["R"], ch["G"], ch["B"]], axis=-1)
    )


@pytest.mark.parametrize(
    "extra,why",
    [
        (["-o", "x.png"], "--aovs writes its channels into an .exr"),
        (["--spp", "1", "-o", "x.exr"], "at least 2 camera samples per pixel"),
        (["--estimator", "series", "--style", "gamma", "-o", "x.exr"],
         "--aovs with estimator 'series'"),
    ],
)
def test_refusals_are_one_line(tmp_path, capsys, extra, why):
    args = ["render", "cornell-box", "--width", "8", "--height", "8", "--aovs", *extra]
    args = [a if not a.startswith("x.") else str(tmp_path / a) for a in args]
    assert main(args) == 2
    err = capsys.readouterr().err.strip()
    assert err.count("\n") == 0 and why in err, err
    assert not list(tmp_path.iterdir())


def test_python_render_returns_the_aovs():
    image, aovs = styletrace.render(
        "cornell-box", style="cel", spp=2, inner="2:8", width=12, height=8, aovs=True
    )
    assert image.shape == (8, 12, 3) and aovs["variance"].shape == (8, 12, 3)
    assert aovs["bias"].shape == aovs["children"].shape == (8, 12)
    c = aovs["children"]  # per sample 0 (left the box) or 2..8; pixels average two
    assert np.all((c >= 0) & (c <= 8)) and c.max() > 2
    assert isinstance(
        styletrace.render("cornell-box", style="cel", spp=2, inner=2, width=12, height=8),
        np.ndarray,
    )
    with pytest.raises(UsageError, match="for spp with aovs=True"):
        api.render("cornell-box", style="cel", spp=1, width=8, height=8, aovs=True)
