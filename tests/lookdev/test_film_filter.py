"""Buffers of films with a reconstruction filter other than a box (`lookdev.film_filter`).

- `positions` draws each camera sample's film position as Mitsuba's render loop does: the rays a
render traced are the rays of those positions, bit for bit, for the independent, stratified and
multijitter samplers, with and without border sampling;
- a restyle equals a fresh render with the new style (the same seed, spp, n) to float rounding for
gaussian (Mitsuba's default: a film with no rfilter), tent, mitchell and box filters, with
sample_border, over several passes, and on a film rendered in tiles (each pass developed in its crop
window, as the render);
- the filter survives the file, and buffers of a box filter keep their format (no positions).
"""
import numpy as np
import pytest

import styletrace
from styletrace.frontends import api
from styletrace.gate import dr, mi
from styletrace.lookdev import film_filter
from styletrace.lookdev.buffer import bytes_per_camera_sample, load_buffer
from styletrace.lookdev.fit import fit
from styletrace.lookdev.record import record, render_buffer
from styletrace.lookdev.restyle import restyle
from styletrace.pipeline import passes as pass_loop
from styletrace.scene.builtin import cornell_box

W, H, SPP, INNER, SEED = 20, 14, 5, 2, 7
#: both images are float32 sums of the same float32 sample values and filter weights, in another
#: order
RTOL, ATOL = 1e-5, 1e-6


def scene_dict(rfilter, border=False, sampler="independent", w=W, h=H):
    sc = cornell_box(w, h)
    film = sc["sensor"]["film"]
    film.pop("rfilter")
    if rfilter is not None:
        film["rfilter"] = rfilter
    film["sample_border"] = border
    sc["sensor"]["sampler"] = {"type": sampler}
    return sc


class Rays(mi.SamplingIntegrator):
    """Keeps the camera rays' directions of the last render."""

    def __init__(self):
        super().__init__(mi.Properties())
        self.d = None

    def sample(self, scene, sampler, ray, medium=None, active=True):
        self.d = mi.Vector3f(ray.d)
        dr.schedule(self.d)
        return mi.Spectrum(0.0), True, []


@pytest.mark.parametrize("sampler", ["independent", "stratified", "multijitter", "owen_sobol"])
@pytest.mark.parametrize("border", [False, True])
def test_positions_are_the_render_loops(sampler, border):
    scene = mi.load_dict(scene_dict({"type": "gaussian"}, border, sampler, 9, 7))
    rays = Rays()
    mi.render(scene, integrator=rays, spp=4, seed=1234)
    sensor = scene.sensors()[0]
    pos = film_filter.positions(sensor, 4, 1234)
    assert pos.shape == (2, (9 + 4 * border) * (7 + 4 * border) * 4)
    cs = mi.ScalarVector2f(sensor.film().crop_size())
    at = mi.Point2f(pos[0], pos[1]) / cs
    ray, _ = sensor.sample_ray_differential(0.0, 0.0, at, mi.Point2f(0.5))
    for i in range(3):
        np.testing.assert_array_equal(np.asarray(ray.d[i]), np.asarray(rays.d[i]))


FILTERS = [None, {"type": "gaussian", "stddev": 0.3}, {"type": "tent", "radius": 1.5},
           {"type": "mitchell"}, {"type": "box"}]


@pytest.mark.parametrize("rfilter", FILTERS, ids=lambda f: "default" if f is None else f["type"])
def test_restyle_equals_a_fresh_render(rfilter):
    kw = dict(spp=SPP, inner=INNER, seed=SEED)
    buf = render_buffer(scene_dict(rfilter), style="cel", **kw)
    assert buf.filtered == (rfilter != {"type": "box"})
    np.testing.assert_allclose(restyle(buf), buf.image, rtol=RTOL, atol=ATOL)
    want = styletrace.render(scene_dict(rfilter), style="gamma", gamma=1.7, **kw)
    np.testing.assert_allclose(restyle(buf, style="gamma", gamma=1.7), want, rtol=RTOL, atol=ATOL)


def test_sample_border():
    kw = dict(spp=SPP, inner=INNER, seed=SEED)
    buf = render_buffer(scene_dict({"type": "gaussian"}, border=True), style="cel", **kw)
    assert buf.header["sample_border"] and buf.camera_samples == (W + 4) * (H + 4) * SPP
    own = buf.arrays["own"].astype(bool)
    counts = np.bincount(buf.arrays["pixel"][own], minlength=W * H)
    assert np.array_equal(counts, np.full(W * H, SPP))
    want = styletrace.render(scene_dict({"type": "gaussian"}, border=True), style="sepia", **kw)
    np.testing.assert_allclose(restyle(buf, style="sepia"), want, rtol=RTOL, atol=ATOL)


@pytest.fixture
def tiled(monkeypatch):
    monkeypatch.setattr(pass_loop, "LANES_PER_PASS", 200)
    monkeypatch.setattr(pass_loop, "TILE_SIDE", 16)
    assert len(pass_loop.tiles(40, 30)) == 9


@pytest.mark.parametrize("rfilter", [{"type": "gaussian"}, {"type": "tent"}, {"type": "box"}],
                         ids=lambda f: f["type"])
def test_a_tiled_film_of_several_passes(tiled, rfilter, tmp_path):
    def scene():
        return mi.load_dict(scene_dict(rfilter, w=40, h=30))
    integ = api.make_integrator(style="cel", inner=2)
    shot, split = pass_loop.Shot(scene(), integ, 3, 1), pass_loop.PassSplit(pass_spp=2)
    for prog, buf in record(shot, split):
        buf.image = prog.image
    assert len(buf.header["passes"]) == 18 and buf.spp == 3
    back = load_buffer(buf.save(str(tmp_path / "b.npz")))
    assert back.header["filter"] == buf.header["filter"]
    np.testing.assert_allclose(restyle(back, style="cel"), buf.image, rtol=RTOL, atol=ATOL)
    *_, want = api.passes(scene(), api.make_integrator("gamma", inner=2), 3, 1, pass_spp=2)
    np.testing.assert_allclose(restyle(back, style="gamma"), want.image, rtol=RTOL, atol=ATOL)
    if buf.filtered:  # each pixel has its own spp samples; others weigh on it through the filter
        own = buf.arrays["own"].astype(bool)
        assert 0 < own.mean() < 1
        counts = np.bincount(buf.arrays["pixel"][own], minlength=40 * 30)
        assert np.array_equal(counts, np.full(40 * 30, 3))


def test_the_filters_format():
    buf = render_buffer(scene_dict(None, w=8, h=6), style="cel", spp=1, inner=1, seed=0)
    assert buf.header["filter"] == {"type": "gaussian", "stddev": 0.5}
    assert buf.header["layout"] == [{"offset": [0, 0], "size": [8, 6], "keep": [0, 6, 0, 8]}]
    per = bytes_per_camera_sample("first_hit", filtered=True)
    assert buf.nbytes == buf.camera_samples * per == buf.camera_samples * 74
    box = render_buffer(scene_dict({"type": "box"}, w=8, h=6), style="cel", spp=1, inner=1)
    assert box.header["filter"] == "box" and "pos" not in box.arrays and "layout" not in box.header


def test_fit_differentiates_through_the_filter():
    buf = render_buffer(scene_dict({"type": "gaussian"}), style="contrast", spp=2, inner=2, seed=3)
    r = fit(buf, style="contrast", target=restyle(buf, style="contrast", c=2.2, pivot=0.3))
    assert abs(r.params["c"] - 2.2) < 1e-3 and abs(r.params["pivot"] - 0.3) < 1e-3


def test_a_version_2_file_of_a_box_filter_still_restyles(tmp_path):
    """Files written before filters were recorded (version 2: no positions, "filter": "box") read
    as before."""
    import json
    box = render_buffer(scene_dict({"type": "box"}, w=8, h=6), style="cel", spp=2, inner=1)
    old = dict(box.header, version=2)
    path = str(tmp_path / "old.npz")
    np.savez(path, header=np.frombuffer(json.dumps(old).encode(), dtype=np.uint8), **box.arrays)
    back = load_buffer(path)
    assert not back.filtered
    np.testing.assert_array_equal(restyle(back, style="sepia"), restyle(box, style="sepia"))
