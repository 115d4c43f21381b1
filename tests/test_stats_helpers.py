"""The statistics of tests/helpers/stats.py on known distributions (numpy only, no rendering)."""
import numpy as np
from helpers.stats import mean_threshold, mean_z, pixel_t_test

K = 16


def rare_light_renders(rng, n, p=1 / 256, big=16.0, base=0.4):
    """K renders of 24 x 24 pixels of an exactly unbiased estimator whose samples are `base`
    except, with probability p, `base + big`: a pixel's value is the mean of n such samples. The
    numbers are those of first_n_hits at stylize_depth 2 on tests/kernel/test_null_surfaces.py's
    diffuse card (sky: 0.8 x 0.5; the lamp, 20 x 0.8, found by a cosine-sampled bounce about once
    in 256), and the reference is path's render: normal, of the same mean."""
    ours = base + big * rng.binomial(n, p, size=(K, 24, 24, 1)) / n
    ref = rng.normal(base + big * p, 0.02, size=(K, 24, 24, 1))
    return ours, ref


def test_pixel_t_test_rejects_an_unbiased_estimator_of_rare_large_samples_at_few_samples():
    """The artefact behind the 'max |t| 47' of first_n_hits at depth 2 (test_recursion.py,
    test_first_n_hits_depth_2_under_a_small_light_per_pixel): with n = 16 samples per pixel and
    render most renders hold no bright sample, the per-pixel t-test rejects a third of the pixels
    while the image means agree; with n = 2048 every render holds several and the test passes.
    Measured on the renderer itself: max |t| 28, 32, 8.8, 5.2 at 4, 16, 64, 256 spp (x inner 4),
    falling as the spp grow, where a bias would make it grow."""
    rng = np.random.default_rng(1)
    ours, ref = rare_light_renders(rng, 16)
    tmax, thr, frac = pixel_t_test(ours, ref)
    assert tmax > 2 * thr and frac > 0.2, (tmax, thr, frac)
    assert np.all(np.abs(mean_z(ours, ref)) < mean_threshold(K, channels=1))
    ours, ref = rare_light_renders(rng, 2048)
    tmax, thr, _ = pixel_t_test(ours, ref)
    assert tmax < thr, (tmax, thr)


def test_pixel_t_test_finds_one_biased_pixel_of_a_normal_estimator():
    """The same test is not blind where its precondition holds: two normal estimators of the same
    mean (sd 0.01 per render) pass, and one pixel made 10% brighter in one of them (t about 14)
    is found."""
    rng = np.random.default_rng(2)
    a = rng.normal(0.5, 0.01, size=(K, 24, 24, 1))
    b = rng.normal(0.5, 0.01, size=(K, 24, 24, 1))
    assert pixel_t_test(a, b)[0] < pixel_t_test(a, b)[1]
    a[:, 5, 7] += 0.05
    tmax, thr, _ = pixel_t_test(a, b)
    assert tmax > thr, (tmax, thr)
