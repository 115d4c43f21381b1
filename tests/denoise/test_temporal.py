"""Temporal reuse (denoise/temporal.py): the frames of one view accumulate their estimates.

- The first frame of a view, and the first after its key changed, is the frame itself, bit for bit.
- Frames of independent noise around one mean: frame k's squared error is the single frame's over
  k (equal weights), within the spread of a mean of 12288 squared Gaussians (relative standard
  error sqrt(2 / 12288) = 1.3%; the tolerance is 5 of them).
- The cap bounds the history's weight: with cap 1 the error stops at half a frame's.
- A change of the light inside a region (a 12-sigma step of the mean) starts those pixels again;
  elsewhere almost none start again (Z = 4: about 6e-5 of them by chance).
- Pixels without an estimate (count 0) show and keep their history (the frame's value where they
  have none); the variance given is used where known, a local stand-in where not.
- The hold keeps the last frame's shown value where the new one moved less than its margin and
  moves it by the excess beyond; after a restart and without a hold the frame's own shows.
- Reprojection: a whole-pixel shift carries the history exactly, a half-pixel one bilinearly (a
  constant stays constant); a surface uncovered by a moving object gets no history (its depth
  differs), so nothing ghosts; the views come from Blender's Vector pass with y up.
- The pipeline's denoisers blend with the history and commit once per frame; without one they are
  what they were.
"""
import numpy as np
import pytest

from styletrace.denoise.temporal import (
    CAP,
    FrameView,
    History,
    box3,
    local_variance,
)
from styletrace.pipeline.denoising import Denoising

SHAPE = (64, 64, 3)
SIGMA = 0.05


def frames(n, mean=0.5, seed=1):
    rng = np.random.default_rng(seed)
    return [mean + SIGMA * rng.standard_normal(SHAPE) for _ in range(n)]


def run(history, images, var=SIGMA ** 2, count=4, key="still"):
    out = []
    for img in images:
        history.start(key)
        out.append(history.blend(img, np.full(SHAPE, var), count))
        history.commit()
    return out


def test_the_first_frame_is_the_frame_itself_bit_for_bit():
    img = frames(1)[0].astype(np.float32)
    h = History()
    assert not h.start("a")
    out = h.blend(img, None, 4)
    assert out.dtype == np.float32 and np.array_equal(out, img)
    h.commit()
    assert h.start("a")
    h.start("b")  # another view: forgotten
    assert h.state is None
    assert np.array_equal(h.blend(img, None, 4), img)


def test_a_still_shots_error_falls_as_one_over_the_frames():
    out = run(History(), frames(8))
    tol = 5 * np.sqrt(2 / np.prod(SHAPE))
    for k, img in enumerate(out, start=1):
        mse = np.mean((img - 0.5) ** 2)
        assert abs(mse * k / SIGMA ** 2 - 1) < tol, (k, mse)


def test_the_history_weighs_at_most_cap_times_the_frame():
    out = run(History(cap=1.0), frames(8))
    tol = 5 * np.sqrt(2 / np.prod(SHAPE))
    # weights 1:1 from the second frame on: the variance settles at
    # v = (v_prev + s^2) / 4 -> s^2 / 3
    mse = np.mean((out[-1] - 0.5) ** 2)
    assert abs(mse / (SIGMA ** 2 / 3) - 1) < 3 * tol
    with pytest.raises(ValueError, match="bad history cap -1"):
        History(cap=-1)
    with pytest.raises(ValueError, match="bad history threshold 0"):
        History(z=0)
    assert CAP >= 64  # a still shot converges over at least 64 frames


def test_a_change_of_the_light_starts_its_pixels_again():
    h = History()
    run(h, frames(8))
    lit = frames(1, seed=9)[0]
    lit[16:48, 16:48] += 12 * SIGMA
    h.start("still")
    out = h.blend(lit, np.full(SHAPE, SIGMA ** 2), 4)
    # inside the region (away from its border, where the 3 x 3 test sees both sides): the frame
    assert np.array_equal(out[18:46, 18:46], lit[18:46, 18:46].astype(np.float32))
    outside = np.ones(SHAPE[:2], bool)
    outside[14:50, 14:50] = False
    h.commit()
    restarted = (h.frames == 1) & outside
    assert restarted.sum() <= 2  # 4032 pixels at 6e-5 each: 0.24 expected


def test_pixels_without_an_estimate_show_and_keep_their_history():
    h = History()
    run(h, frames(3))
    img = frames(1, seed=5)[0]
    count = np.full(SHAPE[:2], 4.0)
    count[:8] = 0
    h.start("still")
    out = h.blend(img, None, count)
    # its history's value, and its history kept for the next frame
    assert np.array_equal(out[:8], h.state.mean[:8].astype(np.float32))
    assert not np.array_equal(out[8:], img[8:].astype(np.float32))
    h.commit()
    assert (h.frames[:8] == 3).all() and (h.frames[8:] == 4).all()
    fresh = History()
    fresh.start("still")
    assert np.array_equal(fresh.blend(img, None, count), img.astype(np.float32))


def test_local_variance_is_the_3x3_neighbourhoods():
    rng = np.random.default_rng(3)
    img = rng.random((5, 6, 3))
    v = local_variance(img)
    p = np.pad(img, ((1, 1), (1, 1), (0, 0)), mode="edge")
    y, x = 2, 3
    assert np.allclose(v[y, x], p[y:y + 3, x:x + 3].reshape(9, 3).var(axis=0))
    assert np.allclose(box3(img)[y, x], p[y:y + 3, x:x + 3].reshape(9, 3).mean(axis=0))


def test_denoising_options_that_differ_only_in_history_are_equal():
    assert Denoising("image", history=History()) == Denoising("image")


def shown_frames(history, images):
    for img in images:
        history.start("still")
        history.hold(history.blend(img, np.full(SHAPE, SIGMA ** 2), 4))
        history.commit()


def test_hold_moves_the_shown_value_only_beyond_its_margin():
    h = History(hold=1.0)
    shown_frames(h, frames(2))
    h.start("still")
    m = frames(1, seed=11)[0]
    h.blend(m, np.full(SHAPE, SIGMA ** 2), 4)
    shown = h.state.shown
    margin = np.sqrt(box3(h._pending.var.mean(axis=-1)))
    d = shown + 0.5 * margin[..., None]  # moved half a margin: held
    d[:4] = shown[:4] + 2.0 * margin[:4, :, None]  # moved two: moves by one
    out = h.hold(d)
    np.testing.assert_allclose(out[4:], shown[4:], rtol=0, atol=1e-6)
    np.testing.assert_allclose(out[:4], shown[:4] + margin[:4, :, None], rtol=1e-5, atol=1e-6)
    h.commit()
    assert np.array_equal(h.state.shown, out)
    # a view's first frame and a history without hold show the frame's own value
    fresh = History()
    fresh.start("v")
    fresh.blend(m, None, 4)
    assert np.array_equal(fresh.hold(d), d.astype(np.float32))
    none = History(hold=0.0)
    shown_frames(none, frames(2))
    none.start("still")
    none.blend(m, None, 4)
    assert np.array_equal(none.hold(d), d.astype(np.float32))
    with pytest.raises(ValueError, match="bad history hold -1"):
        History(hold=-1)


# ---- reprojection ---------------------------------------------------------------------------

H, W = 32, 40


def flat_view(shift=(0.0, 0.0), depth=None):
    """A view whose every pixel saw its surface `shift` (columns, rows) away one frame before."""
    cols, rows = np.meshgrid(np.arange(W) + 0.5, np.arange(H) + 0.5)
    previous = np.stack([cols + shift[0], rows + shift[1]], axis=-1)
    d = np.full((H, W), 2.0) if depth is None else depth
    normal = np.zeros((H, W, 3))
    normal[..., 2] = 1.0
    return FrameView(previous, d, normal)


def test_a_whole_pixel_shift_carries_the_history_exactly():
    texture = np.random.default_rng(4).random((H, W, 3))
    h = History()
    h.start("v", flat_view())
    h.blend(texture, np.full((H, W, 3), 1e-4), 4)
    h.commit()
    h.start("v", flat_view(shift=(3.0, -2.0)))
    s = h.state
    # pixel (r, c) saw, one frame before, what pixel (r - 2, c + 3) saw
    np.testing.assert_allclose(s.mean[2:, :W - 3], texture[:H - 2, 3:], atol=1e-12)
    assert (s.weight[:2] == 0).all() and (s.weight[:, W - 3:] == 0).all()  # from outside
    assert (s.weight[2:, :W - 3] == 4).all()


def test_a_half_pixel_shift_is_bilinear_and_keeps_a_constant():
    h = History()
    h.start("v", flat_view())
    h.blend(np.full((H, W, 3), 0.25), np.full((H, W, 3), 1e-4), 4)
    h.commit()
    h.start("v", flat_view(shift=(0.5, 0.5)))
    inner = h.state.mean[:H - 1, :W - 1]
    np.testing.assert_allclose(inner, 0.25, atol=1e-12)


def test_an_uncovered_surface_gets_no_history():
    """A square in front (depth 1) moves 4 pixels right over a wall (depth 5): where the wall is
    uncovered its history (the square's) is refused; on the square it is carried along."""
    depth0 = np.full((H, W), 5.0)
    depth0[8:24, 8:20] = 1.0
    colour = np.full((H, W, 3), 0.2)
    colour[8:24, 8:20] = 0.9
    h = History()
    h.start("v", flat_view(depth=depth0))
    h.blend(colour, np.full((H, W, 3), 1e-4), 4)
    h.commit()
    depth1 = np.full((H, W), 5.0)
    depth1[8:24, 12:24] = 1.0
    view = flat_view(depth=depth1)
    view.previous[8:24, 12:24, 0] -= 4.0  # the square's pixels saw it 4 columns to the left
    h.start("v", view)
    s = h.state
    assert (s.weight[8:24, 8:12] == 0).all()  # the wall behind the square's old place
    np.testing.assert_allclose(s.mean[8:24, 12:24], 0.9, atol=1e-12)  # the square, carried
    np.testing.assert_allclose(s.mean[:8], 0.2, atol=1e-12)  # the wall elsewhere, kept
    frame = np.full((H, W, 3), 0.2)
    frame[8:24, 12:24] = 0.9
    out = h.blend(frame, np.full((H, W, 3), 1e-4), 4)
    np.testing.assert_array_equal(out[8:24, 8:12], frame[8:24, 8:12].astype(np.float32))


def test_views_from_the_vector_pass():
    """Blender's Vector: (x_prev - x, y_prev - y) with y up; a point that moved 2 pixels right
    and 1 up since the last frame was 2 columns left and 1 row lower."""
    vector = np.zeros((H, W, 4))
    vector[..., 0], vector[..., 1] = -2.0, -1.0
    v = FrameView.from_passes(np.ones((H, W)), np.zeros((H, W, 3)), vector)
    assert tuple(v.previous[5, 7]) == (7.5 - 2.0, 5.5 + 1.0)
