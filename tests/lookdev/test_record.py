"""Recording a film that `pipeline.passes` renders in tiles (crop windows; a film of more than
LANES_PER_PASS pixels).

Each pass of a tiled film covers one tile: its lanes are mapped to the film's pixels
(`record.to_film`) and the pixels a tile shares with its neighbour are left to the neighbour, as in
the render. Before the mapping, every tile's samples landed on the first tile's pixels (the restyle
of a 1100 x 1000 buffer differed from its own render by up to 2.85); a refusal stood in for it until
then. Small films are tiled here by lowering LANES_PER_PASS and TILE_SIDE (3 x 3 tiles of 16 x 12 on
a 40 x 30 film, the last row and column shifted inwards to overlap), so the checks are the same as
at full size:
- every pixel holds exactly spp samples, and each sample's vertex projects into its own pixel (the
  sensor's own projection, `expectation.raster`: independent of the mapping);
- the restyle with the recorded style equals the image the render made, for a buffer of means and
  for a buffer of sequences (`series`);
- `spp` counts a pass of every tile once, and is 0 while a round of tiles is under way.
"""
import numpy as np
import pytest

import styletrace
from styletrace.denoise import expectation as X
from styletrace.frontends import api
from styletrace.lookdev.buffer import load_buffer
from styletrace.lookdev.record import record
from styletrace.pipeline import passes as pass_loop
from styletrace.pipeline.passes import PassSplit, Shot

W, H = 40, 30


@pytest.fixture
def tiled(monkeypatch):
    monkeypatch.setattr(pass_loop, "LANES_PER_PASS", 200)
    monkeypatch.setattr(pass_loop, "TILE_SIDE", 16)
    layout = pass_loop.tiles(W, H)
    # edge tiles shifted inwards: they overlap
    assert len(layout) == 9 and layout[-1].offset == (24, 18)
    return layout


def _box():
    return api.load_scene("cornell-box", W, H)


def test_every_sample_lands_on_its_own_pixel(tiled):
    scene = _box()
    bufs = [b for _, b in record(Shot(scene, api.make_integrator(style="cel", inner=2), 3, 4))]
    buf = bufs[-1]
    a = buf.arrays
    assert buf.header["tiles"] == 9 and len(buf.header["passes"]) == 9 and buf.spp == 3
    assert np.array_equal(np.bincount(a["pixel"], minlength=W * H), np.full(W * H, 3))
    hit = a["slot"] >= 0
    assert hit.mean() > 0.5  # the box and its light fill most of the view
    uv = X.raster(scene, a["p"][:, hit])
    pixel = a["pixel"][hit].astype(np.int64)
    inside = (np.floor(uv[:, 0]) == pixel % W) & (np.floor(uv[:, 1]) == pixel // W)
    # a vertex on a pixel's very edge may round either way
    assert inside.mean() > 0.999, inside.mean()


def test_restyle_equals_the_render_of_a_tiled_film(tiled, tmp_path):
    scene = _box()
    for prog, buf in record(Shot(scene, api.make_integrator(style="cel", inner=2), 2, 1)):
        buf.image = prog.image
    buf.save(str(tmp_path / "b.npz"))
    again = styletrace.restyle(load_buffer(str(tmp_path / "b.npz")), style="cel")
    np.testing.assert_allclose(again, buf.image[..., :3], atol=2e-6)


def test_a_sequence_buffer_of_a_tiled_film_restyles_to_its_render(tiled):
    scene = _box()
    integ = api.make_integrator(style="gamma", inner=4, estimator="series", exposure=1.0)
    for prog, buf in record(Shot(scene, integ, 1, 2)):
        buf.image = prog.image
    assert buf.stores == "sequence" and buf.header["tiles"] == 9
    np.testing.assert_allclose(
        styletrace.restyle(buf, style="gamma", estimator="series", exposure=1.0),
        buf.image[..., :3],
        atol=2e-6,
    )


def test_spp_waits_for_every_tile(tiled):
    scene = _box()
    spp = [
        b.spp
        for _, b in record(Shot(scene, api.make_integrator(style="cel", inner=1), 2, 0),
                           PassSplit(pass_spp=1))
    ]
    assert spp == [0] * 8 + [1] + [1] * 8 + [2]


def test_a_film_of_one_pass_is_recorded():
    scene = api.load_scene("cornell-box", 8, 6)
    prog, buf = next(record(Shot(scene, api.make_integrator(style="cel", inner=1), 1)))
    assert buf.camera_samples == 48
    assert "tiles" not in buf.header and "tile" not in buf.header["passes"][0]
