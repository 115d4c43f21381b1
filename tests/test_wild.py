"""styletrace.wild: the fraction of pixel values outside a style's range, counted against numpy."""
import numpy as np

from styletrace import wild


def test_fraction_counts_values_beyond_the_tolerance():
    img = np.full((10, 10, 3), 0.5, np.float32)        # median |value| 0.5: tolerance 0.05
    img[0, 0, 0] = -0.04                               # inside the tolerance: noise, not wild
    img[0, 1, 1] = -0.06                               # wild
    img[0, 2, 2] = 1.2                                 # wild when hi = 1
    img[0, 3, 0] = np.nan                              # not counted at all
    frac, lo, hi, med = wild.measure(img, 0.0, 1.0)
    assert frac == 2 / 299 and lo == np.float32(-0.06) and hi == np.float32(1.2) and med == 0.5
    assert wild.measure(img, 0.0, None)[0] == 1 / 299  # unbounded above


def test_tame_image_is_not_wild():
    img = np.random.default_rng(0).uniform(0.0, 2.0, (16, 16, 3))
    assert wild.measure(img, 0.0, None)[0] == 0.0
