"""The reference-free measures of benchmarks/real_scenes.py (`styletrace.measures`), on images
with known answers."""
import numpy as np
import pytest

from styletrace import measures


def test_psnr_of_two_seeds_is_the_noise_of_one():
    rng = np.random.default_rng(0)
    base = np.full((64, 64, 3), 0.5)
    sigma = 0.01  # in display space: 0.5 linear is 0.735 sRGB, the slope there 0.84 per linear unit
    a = base + rng.normal(0, sigma, base.shape)
    b = base + rng.normal(0, sigma, base.shape)
    slope = (measures.srgb(np.array(0.5 + 1e-4)) - measures.srgb(np.array(0.5))) / 1e-4
    expected = 10 * np.log10(1 / (slope * sigma) ** 2)
    assert measures.noise_psnr(a, b) == pytest.approx(expected, abs=0.2)
    assert measures.noise_psnr(a, a) == float("inf")


def test_fireflies_are_counted_against_their_neighbourhood_not_in_the_dark():
    img = np.full((20, 20, 3), 0.2)
    img[5, 5] = 50.0                    # a firefly
    img[10, 10] = 0.9                   # bright, but under 5x its neighbours' 0.2
    dark = np.zeros((20, 20, 3))
    dark[3, 3] = 0.02                   # 0.02 among black pixels: below 5 x the 1% floor
    dark[15, 15] = 1.0                  # a firefly in the dark
    assert measures.firefly_share(img) == pytest.approx(1 / 400)
    assert measures.firefly_share(dark) == pytest.approx(1 / 400)


def test_dark_specks_are_counted_in_a_bright_neighbourhood_only():
    img = np.full((20, 20, 3), 0.5)
    img[5, 5] = 0.0                     # a speck: black among 0.5
    img[10, 10] = 0.15                  # darker, but above 0.5 / 5
    img[14:, :] = 0.02                  # a dim stripe (median 0.02 < the 5% floor) ...
    img[18, 18] = 0.0                   # ... where black is no speck
    img[0, 0] = np.nan                  # NaN counts as 0: a speck
    assert measures.speck_share(img) == pytest.approx(2 / 400)
    assert measures.speck_share(np.zeros((8, 8, 3))) == 0.0


def test_clipped_and_crushed_count_pixels_with_every_channel_at_the_end():
    img = np.full((10, 10, 3), 0.3)
    img[0, :] = 2.0                     # clipped
    img[1, :] = (2.0, 2.0, 0.5)         # one channel below: not clipped
    img[2, :] = -0.5                    # crushed
    img[3, :] = 0.00001                 # crushed (sRGB 0.00013)
    assert measures.clipped_share(img) == pytest.approx(0.1)
    assert measures.crushed_share(img) == pytest.approx(0.2)


def test_tone_correlation_is_rank_based_and_sees_a_reversal():
    ramp = np.linspace(0, 1, 32)[None, :, None] * np.ones((32, 32, 3))
    assert measures.tone_correlation(ramp ** 3, ramp, period=1) == pytest.approx(1.0)  # monotone: 1
    assert measures.tone_correlation(1 - ramp, ramp, period=1) == pytest.approx(-1.0)


def test_tone_over_a_mask_compares_only_its_pixels():
    """Two mappings of brightness side by side (an object brightened, the environment beside it
    as it is) break the whole image's rank order; over either part alone it holds."""
    rng = np.random.default_rng(5)
    ref = np.repeat(rng.uniform(0.05, 1.0, (32, 32, 1)), 3, -1)
    img = ref.copy()
    left = np.zeros((32, 32), bool)
    left[:, :16] = True
    img[left] = ref[left] ** 0.2  # the object, gamma-brightened
    whole = measures.tone_correlation(img, ref, 1)
    assert measures.tone_correlation(img, ref, 1, mask=left) == pytest.approx(1.0)
    assert measures.tone_correlation(img, ref, 1, mask=~left) == pytest.approx(1.0)
    assert whole < 0.9, whole
