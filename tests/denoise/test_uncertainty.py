"""The style averaged over D's uncertainty (denoise/expectation.py `spread`, lookdev/restyle.py
`finish_spread`).

- The quadrature is numpy's: SPREAD_NODES are numpy.polynomial.hermite_e.hermegauss(5), weights over
  sqrt(2 pi).
- `finish_spread` of a linear style is the style of the mean (the quadrature is exact for it), and
  with spread 0 it is `finish`.
- `spread` is uncertainty x the relative standard error of each pixel's mean of its samples'
  children means, its square averaged over the 3 x 3 neighbourhood, computed here by numpy from a
  hand-made buffer.
- With uncertainty 0 a render keeps no spread and styles D itself; with the default it keeps one per
  point.
"""

import numpy as np
import pytest

from styletrace.config import settings as S
from styletrace.denoise import expectation as X
from styletrace.errors import UsageError
from styletrace.frontends import api
from styletrace.gate import mi
from styletrace.lookdev.buffer import SPREAD, Buffer
from styletrace.lookdev.restyle import SPREAD_NODES, finish_slot, finish_spread
from styletrace.pipeline.denoising import Denoising
from styletrace.pipeline.passes import Shot
from styletrace.styles.base import Vertex


def test_nodes_are_numpys_gauss_hermite():
    z, w = np.polynomial.hermite_e.hermegauss(5)
    got = sorted(SPREAD_NODES)
    np.testing.assert_allclose([g[0] for g in got], np.sort(z), atol=1e-7)
    np.testing.assert_allclose(
        [g[1] for g in got], w[np.argsort(z)] / np.sqrt(2 * np.pi), atol=1e-7
    )


def vertex(n):
    zero = mi.Vector3f(np.zeros(n, np.float32), np.zeros(n, np.float32), np.ones(n, np.float32))
    return Vertex(
        p=mi.Point3f(zero),
        n=zero,
        wo=zero,
        view=mi.Vector3f(0, 0, -1),
        depth=mi.UInt32(np.zeros(n, np.uint32)),
    )


def test_a_linear_style_is_unchanged_and_spread_zero_is_finish():
    mean = mi.Color3f(
        np.array([0.2, 0.5, 0.9], np.float32),
        np.array([0.1, 0.4, 0.3], np.float32),
        np.array([0.3, 0.2, 0.6], np.float32),
    )
    v = vertex(3)
    ident = S.parse_slot(
        {"style": "identity", "inner_samples": 1, "estimator": "direct"}, context="test"
    )
    got = finish_spread(ident, mean, v, mi.Float([0.1, 0.2, 0.3]))
    np.testing.assert_allclose(np.array(got), np.array(mean), rtol=1e-6)
    cel = S.parse_slot(
        {
            "style": "cel",
            "thresholds": "0.3,0.6",
            "levels": "0.1,0.5,0.9",
            "inner_samples": 1,
            "estimator": "direct",
        },
        context="test",
    )
    np.testing.assert_allclose(
        np.array(finish_spread(cel, mean, v, mi.Float(0.0))),
        np.array(finish_slot(cel, mean, v)),
        rtol=1e-6,
    )
    # a mean on a threshold, with spread: between the two bands, not on either
    on = mi.Color3f(0.3, 0.3, 0.3)
    lo, hi = (
        np.array(finish_slot(cel, mi.Color3f(x, x, x), vertex(1)))[:, 0] for x in (0.29, 0.31)
    )
    mid = np.array(finish_spread(cel, on, vertex(1), mi.Float(0.2)))[:, 0]
    assert np.all(np.minimum(lo, hi) < mid) and np.all(mid < np.maximum(lo, hi))


def test_spread_is_the_relative_standard_error():
    rng = np.random.default_rng(3)
    w, h, per = 4, 3, 5
    pixel = np.repeat(np.arange(w * h), per).astype(np.uint32)
    mean = rng.uniform(0.2, 1.0, (3, pixel.size)).astype(np.float32)
    slot = np.zeros(pixel.size, np.int8)
    # pixel 0 keeps one sample with a vertex: no standard error (0 in the average)
    slot[: per - 1] = -1
    buf = Buffer({"width": w, "height": h}, {"pixel": pixel, "slot": slot, "mean": mean})
    emission = np.zeros((pixel.size, 3))
    emission[per : 2 * per] = 0.05  # pixel 1's samples emit: the reflected part is what counts
    got = X.spread(buf, emission, 0.3)
    lum = mean.astype(np.float64).mean(0) - emission.mean(1)
    rel2 = np.zeros(w * h)
    for p in range(1, w * h):
        x = lum[p * per : (p + 1) * per]
        rel2[p] = (x.std(ddof=1) / np.sqrt(per) / abs(x.mean())) ** 2
    rel2 = rel2.reshape(h, w)
    for y in range(h):
        for x in range(w):
            near = [
                rel2[min(max(y + dy, 0), h - 1), min(max(x + dx, 0), w - 1)]
                for dy in (-1, 0, 1)
                for dx in (-1, 0, 1)
            ]
            assert got[y, x] == pytest.approx(min(0.3 * np.sqrt(np.mean(near)), 1.0), rel=1e-6)


@pytest.mark.parametrize("bad", [-0.1, float("inf"), "x", True, 11])
def test_bad_uncertainty_is_refused(bad):
    with pytest.raises(
        UsageError, match=r"bad value .* for denoise uncertainty: expected a number from 0"
    ):
        X.check_uncertainty(bad)


def test_uncertainty_zero_styles_d_itself():
    scene = api.load_scene("cornell-box", 16, 16)
    integ = api.make_integrator(style="cel", inner=2)
    shot = Shot(scene, integ, 2, 1)
    img0, b0 = X.render_denoised_expectation(shot, Denoising("expectation", coverage=4))
    img1, b1 = X.render_denoised_expectation(
        shot, Denoising("expectation", coverage=4, uncertainty=0.3)
    )
    assert X.UNCERTAINTY == 0 and b0.header["denoise"]["uncertainty"] == 0  # the default
    assert SPREAD not in b0.arrays and SPREAD in b1.arrays
    assert b1.header["denoise"]["uncertainty"] == 0.3 and np.all(b1.arrays[SPREAD] >= 0)
    # the same D at the same points
    np.testing.assert_array_equal(b0.arrays["mean"], b1.arrays["mean"])
    assert np.abs(img0 - img1).max() > 1e-3  # and a different style of it
