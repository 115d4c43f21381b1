"""Coverage points (denoise/coverage.py): k stratified first hits per pixel where the style meets D.

- The points are stratified: the j-th point of a pixel lies in cell (j mod m, j div m) of an m x m
  grid over the pixel. Checked by projecting every point's vertex back onto the film
  (`expectation.raster`, the sensor's own projection), on a plane that fills the view; an
  independent placement puts 15 of 16 points outside their cell. The same holds where the film is
  rendered in tiles (each tile's points are mapped to the film's pixels and D's), and in a crop
  window of the film (the sensor's position sample spans the crop window: the points were placed as
  if it spanned the whole film until this test), and the points' buffer restyles to the denoised
  image.
- `coverage` values: "auto" is 64 where it fits the buffer's cap and the largest square that fits
  elsewhere; anything else than "auto", 0 or a square is refused in one line naming the value, and
  so is a count over the cap.
"""

import math

import numpy as np
import pytest

import styletrace
from styletrace.denoise import coverage as C
from styletrace.denoise import expectation as X
from styletrace.errors import UsageError
from styletrace.frontends import api
from styletrace.gate import mi
from styletrace.pipeline.denoising import Denoising
from styletrace.pipeline.passes import Shot

RES = 12


def plane(crop=None):
    T = mi.ScalarTransform4f
    film = {"type": "hdrfilm", "width": RES, "height": RES, "rfilter": {"type": "box"}}
    if crop:  # a crop window: x, y, width, height
        film.update(zip(("crop_offset_x", "crop_offset_y", "crop_width", "crop_height"), crop))
    grey = {"type": "diffuse", "reflectance": {"type": "rgb", "value": [0.5] * 3}}
    return api.load_scene(
        {
            "type": "scene",
            "sensor": {
                "type": "perspective",
                "fov": 30,
                "to_world": T().look_at(origin=[0, 0, 4], target=[0, 0, 0], up=[0, 1, 0]),
                "film": film,
            },
            "plane": {"type": "rectangle", "to_world": T().scale(3.0), "bsdf": grey},
            "sky": {"type": "constant", "radiance": {"type": "rgb", "value": [1.0] * 3}},
        }
    )


@pytest.mark.parametrize(
    "k,tiled,crop",
    [
        (4, False, None),
        (16, False, None),
        (4, True, None),
        (4, False, (3, 2, 7, 9)),
        (4, True, (1, 0, 11, 10)),
    ],
)
def test_each_point_lies_in_its_own_cell(k, tiled, crop, monkeypatch):
    # 2 x 2 crop windows of 8 x 8, the second row and column shifted inwards (pipeline.passes)
    if tiled:
        from styletrace.pipeline import passes as pass_loop

        monkeypatch.setattr(pass_loop, "LANES_PER_PASS", 64)
        monkeypatch.setattr(pass_loop, "TILE_SIDE", 8)
        assert len(pass_loop.tiles(*(crop[2:] if crop else (RES, RES)))) == 4
    scene = plane(crop)
    w = crop[2] if crop else RES
    image, buf = X.render_denoised_expectation(
        Shot(scene, api.make_integrator(style="cel", inner=1), 1, 5),
        Denoising("expectation", coverage=k),
    )
    assert buf.header.get("tiles", 1) == (4 if tiled else 1)
    np.testing.assert_allclose(styletrace.restyle(buf, style="cel"), image, atol=2e-6)
    a = buf.arrays
    assert buf.camera_samples == buf.width * buf.height * k and buf.width == w
    assert np.all(a["slot"] >= 0)
    uv = X.raster(scene, a["p"])
    pixel = a["pixel"].astype(np.int64)
    assert np.all(np.floor(uv[:, 0]) == pixel % w) and np.all(np.floor(uv[:, 1]) == pixel // w)
    m = math.isqrt(k)
    j = np.arange(buf.camera_samples) % k  # the lane's point within its pixel
    cell = np.floor((uv - np.floor(uv)) * m).astype(np.int64)
    assert np.array_equal(cell[:, 0], j % m) and np.array_equal(cell[:, 1], j // m)


def test_points_differ_by_seed_and_stay_by_seed():
    scene = plane()
    integ = api.make_integrator(style="cel", inner=1)
    p = [
        X.render_denoised_expectation(Shot(scene, integ, 1, s),
                                      Denoising("expectation", coverage=4))[1].arrays["p"]
        for s in (1, 1, 2)
    ]
    assert np.array_equal(p[0], p[1]) and not np.allclose(p[0], p[2])


def test_auto_fits_the_buffer():
    assert C.resolve_k("auto", 128, 128) == C.DEFAULT_K == 64
    assert C.resolve_k("auto", 1024, 1024) == 4  # 4 Mi points at most
    # not one point per pixel fits: g at the camera samples
    assert C.resolve_k("auto", 4096, 4096) == 0
    assert C.resolve_k("16", 64, 64) == 16 and C.resolve_k(0, 64, 64) == 0


@pytest.mark.parametrize("bad", [3, -4, "x", 2.5, True, "16.0"])
def test_bad_values_are_refused(bad):
    with pytest.raises(UsageError, match=r"bad value .* for coverage: expected 'auto', 0"):
        C.check_k(bad)


def test_a_count_over_the_cap_is_refused():
    with pytest.raises(
        UsageError,
        match=r"bad value 64 for coverage: 512x512 .* over the buffer's cap .* at most 16",
    ):
        C.resolve_k(64, 512, 512)


@pytest.mark.parametrize("scale", [1, 2])
def test_points_read_d_at_their_own_film_position(scale):
    """D given on a grid of `scale` x the film's pixels per axis, linear in the film position:
    each point's D is that linear function at the point's own film position (bilinear
    interpolation reproduces it), found by projecting the point back through the sensor; for
    scale 2 the lookup lands in the right sub-pixel (`benchmarks/denoise_subpixel.py` uses it)."""
    from styletrace.kernel.guides import Guides

    scene = plane()
    n = RES * scale
    y, x = np.mgrid[0:n, 0:n].astype(np.float32)
    d = np.stack([(x + 0.5) / scale, (y + 0.5) / scale, np.ones_like(x)], -1)
    same = np.full((n, n, 3), 0.5, np.float32)
    normal = np.zeros((n, n, 3), np.float32)
    normal[..., 2] = 1.0
    field = X.Field(d, Guides(same, normal, np.zeros_like(normal), normal), 10.0)
    buf = C.points(
        scene, api.make_integrator(style="identity", inner=1), field, 4, seed=3, scale=scale
    )
    uv = X.raster(scene, buf.arrays["p"])
    inside = np.all((uv > 0.5) & (uv < RES - 0.5), axis=1)  # away from the clamped border
    assert inside.sum() > 300
    np.testing.assert_allclose(buf.arrays["mean"][:2, inside].T, uv[inside], atol=2e-3)
