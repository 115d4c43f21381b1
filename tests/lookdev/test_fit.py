"""Fitting θ recovers the parameters a target was restyled with.

Tolerances: contrast and the colour map are smooth in θ (the image is affine in their parameters),
so gradient descent converges to the exact θ; we accept 1e-3 (contrast) and 1e-2 per colour channel
(colour stops with few samples near them converge last), far below a visible difference. A cel
threshold is only identifiable up to the gap between the brightnesses of neighbouring camera
samples: any threshold with no sample's brightness between it and the true one gives the identical
image, which is what we require; its levels must then be within 1e-3.
"""
import numpy as np
import pytest

from styletrace.errors import UsageError
from styletrace.lookdev.fit import fit
from styletrace.lookdev.record import render_buffer
from styletrace.lookdev.restyle import restyle
from styletrace.styles.gradient import Gradient

GREY5 = "0:0.5,0.5,0.5;0.3:0.5,0.5,0.5;0.6:0.5,0.5,0.5;0.9:0.5,0.5,0.5;1.2:0.5,0.5,0.5"


@pytest.fixture(scope="module")
def buf():
    return render_buffer("cornell-box", style="cel", spp=4, inner=4, seed=3, width=48, height=48)


@pytest.fixture(scope="module")
def u(buf):
    """Brightness of each stylized camera sample's child mean."""
    return buf.arrays["mean"][:, buf.arrays["slot"] >= 0].mean(axis=0)


def test_contrast(buf):
    r = fit(buf, style="contrast", target=restyle(buf, style="contrast", c=2.2, pivot=0.3))
    assert abs(r.params["c"] - 2.2) < 1e-3 and abs(r.params["pivot"] - 0.3) < 1e-3
    assert r.loss < 1e-8 and r.iterations < 300  # stopped at the loss tolerance


def test_color_map(buf, u):
    truth = Gradient.parse("heat").stops
    # the gradient's own span as the range (absolute mapping), so a stop is identifiable where u
    # reaches it
    span = (truth[0][0], truth[-1][0])
    target = restyle(buf, style="color_map", gradient="heat", range=span)
    r = fit(buf, style="color_map", target=target, gradient=GREY5, range=span, fixed=("range",))
    got = r.params["gradient"].stops
    pos = [p for p, _ in truth]
    checked = 0
    for i, ((p, want), (q, col)) in enumerate(zip(truth, got)):
        assert p == q  # positions stay
        lo = pos[i - 1] if i > 0 else -np.inf
        hi = pos[i + 1] if i + 1 < len(pos) else np.inf
        if not np.any((u > lo) & (u < hi)):
            continue  # no sample sees this stop: it cannot be identified
        np.testing.assert_allclose(col, want, atol=1e-2)
        checked += 1
    assert checked >= 3


def test_cel(buf, u):
    truth = dict(thresholds=(0.1, 0.4), levels=(0.05, 0.3, 0.8))
    r = fit(
        buf,
        style="cel",
        target=restyle(buf, style="cel", **truth),
        thresholds=(0.2, 0.6),
        levels=(0.2, 0.5, 0.6),
    )
    for got, want in zip(r.params["thresholds"], truth["thresholds"]):
        assert not np.any((u - got) * (u - want) < 0), (got, want)
    np.testing.assert_allclose(r.params["levels"], truth["levels"], atol=1e-3)


def test_without_the_surrogate_cel_thresholds_do_not_move(buf):
    """The surrogate is what makes thresholds fittable: with τ ~ 0 the sigmoid is a step, no
    gradient."""
    truth = dict(thresholds=(0.1, 0.4), levels=(0.05, 0.3, 0.8))
    r = fit(buf, style="cel", target=restyle(buf, style="cel", **truth), thresholds=(0.2, 0.6),
            levels=(0.2, 0.5, 0.6), tau=1e-12, tau_end=1e-12, iterations=50)
    assert r.params["thresholds"] == pytest.approx((0.2, 0.6), abs=1e-6)


def test_bad_requests(buf):
    target = restyle(buf)
    with pytest.raises(UsageError, match="bad target image of shape \\(2, 2, 3\\)"):
        fit(buf, style="cel", target=np.zeros((2, 2, 3)))
    with pytest.raises(UsageError, match="style 'halftone' cannot be fitted"):
        fit(buf, style="halftone", target=target)
    with pytest.raises(UsageError, match="style 'identity' has no parameter to fit"):
        fit(buf, style="identity", target=target)
    with pytest.raises(UsageError, match="bad fixed parameter 'nope'"):
        fit(buf, style="cel", target=target, fixed=("nope",))


def test_the_printed_restyle_line_is_accepted_and_gives_the_fitted_image(buf, tmp_path, capsys):
    """Thresholds that differ only past the 6 digits `styletrace fit` prints (here: a start
    0.2,0.2000001 that a tiny step leaves in place) once printed as 0.2,0.2, which the command line
    refuses ("must increase"): the printed values are the fit's, strictly increasing as printed."""
    import shlex

    from styletrace.frontends.cli import main
    path, target = str(tmp_path / "b.npz"), str(tmp_path / "t.exr")
    buf.save(path)
    from styletrace.images import write_image
    write_image(restyle(buf, style="cel", thresholds=(0.3,), levels=(0.1, 0.8)), target)
    fitted = str(tmp_path / "fitted.exr")
    assert main(["fit", path, "--style", "cel", "--target", target, "--set",
                 "thresholds=0.2,0.2000001", "--iterations", "1", "--lr", "1e-12", "-o",
                 fitted]) == 0
    line = capsys.readouterr().out.strip().splitlines()[-1]
    assert "thresholds=0.2,0.200001 " in line
    again = str(tmp_path / "again.exr")
    assert main(shlex.split(line)[1:] + ["-o", again]) == 0, capsys.readouterr().err
    from styletrace.gate import mi
    assert np.array_equal(np.array(mi.Bitmap(again)), np.array(mi.Bitmap(fitted)))


@pytest.mark.parametrize("values,shown", [
    ((0.199919, 0.199919), "0.199919,0.19992"),
    ((0.5, 0.4, 0.4), "0.5,0.500001,0.500002"),
    ((0.0, 0.0), "0,1e-06"),
    ((-2.0, -2.0), "-2,-1.99999"),
    ((0.1234567, 0.9), "0.123457,0.9"),
])
def test_increasing_values_are_strictly_increasing_as_printed(values, shown):
    from styletrace.lookdev.fit import as_printed
    from styletrace.styles import style_class
    p = next(q for q in style_class("cel").params if q.name == "thresholds")
    assert p.show(as_printed(p, values, increasing=True)) == shown
