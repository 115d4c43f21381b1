"""The one-sample-per-pixel view of a buffer (`restyle.per_pixel`), for restyles while a slider
moves.

- A restyle of the view is the image of the whole buffer restricted to the chosen samples: each
  pixel the value its sample has in the whole buffer's restyle (`sample_values`, computed here
  with the samples picked on the host, independently of the view's own picking), bit for bit; and
  the same as restyling a buffer built on the host of just those samples. Checked on a buffer of
  two passes (a pixel's samples apart, not in pixel order), for the first and the second sample.
- The view is kept; a point beyond every pixel's samples leaves them all out; a sequence buffer
  and a negative point are refused in one line.
"""
import numpy as np
import pytest

from styletrace.errors import UsageError
from styletrace.lookdev.buffer import Buffer
from styletrace.lookdev.record import render_buffer
from styletrace.lookdev.restyle import per_pixel, prepare_slots, restyle, sample_values, slots_for

W, H = 14, 10


@pytest.fixture(scope="module")
def buf():
    # 2 passes of 2 spp: each pixel's 4 samples lie in two blocks, one per pass
    b = render_buffer("cornell-box", style="cel", spp=4, inner=2, seed=3, width=W, height=H,
                      pass_spp=2)
    assert len(b.header["passes"]) == 2
    return b


def chosen(buf, point):
    """The index of each pixel's `point`-th sample, found on the host."""
    pixel = buf.arrays["pixel"]
    out = np.full(W * H, -1)
    seen = np.zeros(W * H, dtype=int)
    for i, p in enumerate(pixel):
        if seen[p] == point:
            out[p] = i
        seen[p] += 1
    assert np.all(out >= 0)
    return out


@pytest.mark.parametrize("point", [0, 1])
@pytest.mark.parametrize("style", ["cel", "hatching"])
def test_the_view_restyles_to_the_whole_buffer_at_its_samples(buf, style, point):
    view = per_pixel(buf, point)
    assert view.camera_samples == W * H
    assert view.header["per_pixel"] == {"point": point, "of": 4 * W * H}
    got = restyle(view, style=style)
    values = sample_values(buf, prepare_slots(buf, slots_for(buf, style=style)))
    idx = chosen(buf, point)
    want = np.stack([np.asarray(values[c])[idx] for c in range(3)], -1).reshape(H, W, 3)
    np.testing.assert_array_equal(got, want)
    # the same samples as a buffer of their own, made on the host
    header = dict(buf.header, passes=[{"spp": 1, "seed": 0}])
    names = [k for k in buf.arrays if not k.startswith("pilot_")]
    own = Buffer(header, {**{k: buf.arrays[k][..., idx] for k in names},
                          **{k: buf.arrays[k] for k in buf.arrays if k.startswith("pilot_")}})
    np.testing.assert_array_equal(restyle(own, style=style), got)
    assert np.abs(got - restyle(buf, style=style)).max() > 0  # one sample is not the mean of 4


def test_the_view_is_kept_and_refused_where_it_cannot_be(buf):
    assert per_pixel(buf) is per_pixel(buf)
    view = per_pixel(buf, 4)  # no pixel has a fifth sample: all left out
    assert view.camera_samples == 0
    with pytest.raises(UsageError, match="bad value -1 for point"):
        per_pixel(buf, -1)
    seq = render_buffer("cornell-box", style="gamma", estimator="series", spp=1, inner=2,
                        width=4, height=4)
    with pytest.raises(UsageError, match="needs a buffer of children means"):
        per_pixel(seq)
