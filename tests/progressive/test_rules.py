"""The progressive schedule's rules (`progressive.rules`): when to denoise, when a new denoised
image may replace the one on screen, when a quick preview serves, how small a draft is."""
from styletrace.progressive.rules import (
    DRAFT_PIXELS,
    GROWTH,
    denoise_now,
    draft_size,
    quick_serves,
    worth_showing,
)


def test_denoise_now_spends_at_most_about_half_the_time_denoising():
    # the first pass that can be denoised and the last always are
    assert denoise_now(1, 4, 1.6, []) and denoise_now(4, 4, 0.1, [5.0])
    # passes of 1.6 s, denoising of 5 s (400x300, Denoise expectation): 3 of 8 passes shown
    shown, since, spent = [], 0.0, []
    for k in range(1, 9):
        since += 1.6
        if denoise_now(k, 8, since, spent):
            shown.append(k)
            spent.append(5.0)
            since = 0.0
    assert shown == [1, 5, 8]
    # passes slower than the denoising: every pass
    assert all(denoise_now(k, 8, 2.0, [1.0]) for k in range(1, 9))


def test_only_ratios_of_times_decide():
    for k in range(1, 9):
        for since, spent in ((1.6, [5.0]), (5.0, [5.0]), (0.1, [])):
            assert denoise_now(k, 8, since, spent) == denoise_now(k, 8, 10 * since,
                                                                  [10 * s for s in spent])


def test_a_new_denoised_image_takes_growth_times_the_camera_samples():
    assert GROWTH == 2
    assert worth_showing(1, 0) and worth_showing(2, 1) and not worth_showing(3, 2)
    shown = [0]
    for spp in range(1, 17):
        if worth_showing(spp, shown[-1]):
            shown.append(spp)
    assert shown[1:] == [1, 2, 4, 8, 16]


def test_a_quick_preview_serves_over_one_camera_sample_only():
    assert quick_serves(1) and not quick_serves(2) and not quick_serves(16)


def test_the_draft_keeps_the_aspect_within_its_pixels():
    assert draft_size(100, 80) == (100, 80)  # small views keep their size
    assert draft_size(512, 512) == (139, 139)  # each side rounded: 139^2 is about DRAFT_PIXELS
    w, h = draft_size(1920, 1080)
    assert abs(w * h / DRAFT_PIXELS - 1) < 0.02 and abs(w / h - 1920 / 1080) < 0.02
