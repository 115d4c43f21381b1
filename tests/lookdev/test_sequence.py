"""Sequence buffers: the unbiased estimators replayed over each camera sample's stored children
and uniforms equal a fresh render with the same seed; where the replay needs more than is stored
it is refused."""
import numpy as np
import pytest
from helpers.same_render import assert_same_render

import styletrace
from styletrace.errors import UsageError
from styletrace.lookdev import record as record_module
from styletrace.lookdev.buffer import (
    MAX_SEQUENCE_CAMERA_SAMPLES,
    bytes_per_camera_sample,
    load_buffer,
)
from styletrace.lookdev.fit import fit
from styletrace.lookdev.record import render_buffer
from styletrace.lookdev.restyle import replay_lanes, restyle
from styletrace.scene.builtin import cornell_box

W, H, SPP, INNER, SEED = 16, 12, 2, 4, 7
#: "up to float rounding": both images are float32 means of the same per-sample float32 values
RTOL, ATOL = 1e-5, 1e-6

#: (style, estimator, new parameters) for every unbiased estimator whose sequence does not depend on
#: θ
CASES = [
    ("gamma", "series", {"gamma": 1.8}),
    ("gamma", "series_single", {"gamma": 1.8}),
    ("reinhard", "series", {"white": 0.7}),
    ("gamma", "telescoping", {"gamma": 1.8}),
    ("tie_dye", "ustat", {"phases": "0.3,0.2,0.1"}),
    ("tie_dye", "naive", {"phases": "0.3,0.2,0.1"}),
    ("contrast+sepia", "combined", {"contrast.c": 1.5, "contrast.pivot": 0.3}),
    ("gamma+sepia", "combined", {"gamma.gamma": 1.8}),
]


def fresh(style, estimator, spp=SPP, inner=INNER, **params):
    return styletrace.render(
        "cornell-box",
        style=style,
        estimator=estimator,
        spp=spp,
        inner=inner,
        seed=SEED,
        width=W,
        height=H,
        **params,
    )


def record(style, estimator, spp=SPP, inner=INNER):
    return render_buffer(
        "cornell-box",
        style=style,
        estimator=estimator,
        spp=spp,
        inner=inner,
        seed=SEED,
        width=W,
        height=H,
    )


@pytest.mark.parametrize("style,estimator,new", CASES, ids=[f"{c[0]}-{c[1]}" for c in CASES])
def test_restyle_with_new_parameters_equals_a_fresh_render(style, estimator, new):
    buf = record(style, estimator)
    assert buf.stores == "sequence" and buf.arrays["seq_kind"].sum() > 0
    before = fresh(style, estimator)
    assert_same_render(buf.image, before, SPP)  # recording does not change the render
    out = restyle(buf, **new)
    want = fresh(style, estimator, **new)
    np.testing.assert_allclose(out, want, rtol=RTOL, atol=ATOL)
    assert np.abs(want - before).max() > 0.05  # the new parameters do change the image


def test_fewer_pilot_samples_replay_a_prefix():
    """series with n = 2 asks for the recorded (n = 4) uniform, then a prefix of the stored
    children."""
    buf = record("gamma", "series")
    np.testing.assert_allclose(
        restyle(buf, inner=2, gamma=1.8),
        fresh("gamma", "series", inner=2, gamma=1.8),
        rtol=RTOL,
        atol=ATOL,
    )


@pytest.mark.parametrize(
    "change", [dict(inner=16), dict(estimator="direct"), dict(estimator="telescoping")]
)
def test_a_replay_that_needs_more_than_is_stored_is_refused(change):
    buf = record("gamma", "series")
    with pytest.raises(
        UsageError,
        match=r"cannot restyle this buffer: on \d+ of 384 camera samples it asks for a "
        r"child or uniform number beyond the stored ones .*this estimator needs more",
    ):
        restyle(buf, **change)


def test_refusal_is_per_camera_sample_and_exact_where_not_refused():
    """Cumulative truncation (series_recursive) continues with a probability set by the terms'
    magnitudes, so a new gamma changes how many children some samples ask for. At 1 spp a pixel
    is its one camera sample: every sample the replay accepts equals the fresh render, the
    refused ones are those that differ."""
    buf = record("gamma", "series_recursive", spp=1)
    np.testing.assert_allclose(restyle(buf), buf.image, rtol=RTOL, atol=ATOL)
    with pytest.raises(UsageError, match="estimator 'series_recursive' cannot restyle this buffer"):
        restyle(buf, gamma=1.8)
    values, bad = replay_lanes(buf, gamma=1.8)
    want = fresh("gamma", "series_recursive", spp=1, gamma=1.8).reshape(-1, 3)
    assert 0 < bad.sum() < bad.size / 2
    np.testing.assert_allclose(values[~bad], want[~bad], rtol=RTOL, atol=ATOL)
    assert np.any(np.abs(values[bad] - want[bad]).max(axis=1) > 1e-3)


def test_a_full_pool_keeps_each_sample_s_prefix(monkeypatch):
    """With room for 3 children per camera sample on average some samples' sequences are cut: the
    samples whose sequence was kept whole replay exactly, the cut ones are refused."""
    monkeypatch.setattr(record_module, "budget", lambda slots: 3)
    buf = record("gamma", "series", spp=1)
    assert buf.header["events_per_sample"] == 3
    values, bad = replay_lanes(buf)
    assert 0 < bad.sum()
    np.testing.assert_allclose(values[~bad], buf.image.reshape(-1, 3)[~bad], rtol=RTOL, atol=ATOL)
    with pytest.raises(UsageError, match="this estimator needs more"):
        restyle(buf)


def test_first_object_hit_replays_the_styled_objects():
    def scene(**params):
        s = cornell_box(W, H)
        s["large-box"]["bsdf"] = {
            "type": "styled",
            "style": "gamma",
            "estimator": "series",
            "inner_samples": INNER,
            **params,
            "bsdf": {"type": "diffuse"},
        }
        return s
    kw = dict(style="identity", spp=SPP, seed=SEED, stylize="first_object_hit")
    buf = render_buffer(scene(), **kw)
    assert buf.stores == "sequence"
    assert_same_render(buf.image, styletrace.render(scene(), **kw), SPP)
    np.testing.assert_allclose(restyle(buf, gamma=1.6), styletrace.render(scene(gamma=1.6), **kw),
                               rtol=RTOL, atol=ATOL)


def test_file_round_trip_and_size(tmp_path):
    buf = record("gamma", "series")
    back = load_buffer(buf.save(str(tmp_path / "s.npz")))
    assert back.stores == "sequence"
    np.testing.assert_array_equal(restyle(back, gamma=1.5), restyle(buf, gamma=1.5))
    a = buf.arrays
    children = int(a["seq_kind"].sum())
    uniforms = int(a["seq_count"].sum()) - children
    assert a["child"].shape == (3, children) and a["uniform"].shape == (uniforms,)
    # the fixed fields, as docs/lookdev.md says
    assert bytes_per_camera_sample("first_hit", "sequence") == 57
    assert buf.nbytes == 57 * buf.camera_samples + 13 * children + 5 * uniforms


def test_the_sequence_cap_and_fit():
    with pytest.raises(UsageError, match=f"over the cap of {MAX_SEQUENCE_CAMERA_SAMPLES}"):
        render_buffer(
            "cornell-box",
            style="gamma",
            estimator="series",
            spp=1,
            inner=1,
            width=1025,
            height=1024,
        )
    with pytest.raises(UsageError, match="fit needs a buffer of the children's mean"):
        fit(record("gamma", "series"), target=np.zeros((H, W, 3), np.float32))



class OneUniform:
    """An estimator that asks for one uniform number and returns it: the smallest request there
    is."""

    def run(self, draw, carry, uniform, active, like):
        u, carry = uniform(carry)
        return like(u), carry


class TwoChildren:
    def run(self, draw, carry, uniform, active, like):
        a, carry = draw(carry)
        b, carry = draw(carry)
        return a + 10 * b, carry


@pytest.mark.parametrize("estimator,want,bad", [
    (OneUniform(), [0.0, 0.25, 0.0, 0.0], [True, False, True, True]),
    (TwoChildren(), [0.0, 0.0, 0.0, 2.0 + 10 * 3.0], [True, True, True, False]),
])
def test_replay_reads_each_sample_s_own_events_and_nothing_past_them(
    monkeypatch, estimator, want, bad
):
    """Hand-made sequences: sample 0 stores nothing, 1 a uniform, 2 a child, 3 two children."""
    import drjit as dr
    import mitsuba as mi

    from styletrace.config.settings import parse_slot
    from styletrace.lookdev import sequence

    arrays = {
        "seq_count": np.array([0, 1, 1, 2], np.uint32),
        "seq_kind": np.array([0, 1, 1, 1], np.uint8),
        "child": np.array([[1.0, 2.0, 3.0]] * 3, np.float32),
        "uniform": np.array([0.25], np.float32),
    }
    monkeypatch.setattr(sequence, "make_estimator", lambda slot, level, v: estimator)
    total, flagged = sequence.replay(sequence.device_arrays(arrays), mi.Int32(0, 0, 0, 0),
                                     [parse_slot({"style": "gamma"})], None)
    dr.eval(total, flagged)
    np.testing.assert_array_equal(np.asarray(flagged, dtype=bool), bad)
    good = ~np.asarray(bad)
    np.testing.assert_allclose(np.asarray(total[0])[good], np.asarray(want)[good])


def test_a_sample_whose_replay_asks_one_event_past_its_stored_ones_is_refused(monkeypatch):
    """series_recursive with n = 1 asks uniform, child, uniform, ... With room for one uniform
    per camera sample (and one child on average) no sample keeps more than [uniform, child]: the
    third request lies just past every sample's stored events (where the next sample's begin), so
    every hit sample is refused."""
    monkeypatch.setattr(record_module, "budget", lambda slots: 1)
    buf = record("gamma", "series_recursive", spp=1, inner=1)
    assert buf.arrays["seq_count"].max() == 2
    _, bad = replay_lanes(buf)
    np.testing.assert_array_equal(bad, buf.arrays["slot"] >= 0)
