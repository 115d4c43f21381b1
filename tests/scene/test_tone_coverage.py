"""Tone-level coverage on a scene whose brightness range is set by a window (docs/look.md): at
defaults every hatching level and every cel band covers a fair share of the image, where a linear
ramp between the 5% and 95% brightness quantiles (the default before) put most of the room into
one level."""
import numpy as np
import pytest
from helpers.look_scenes import window_room

import styletrace
from styletrace.frontends.api import load_scene, make_integrator, resolve_defaults
from styletrace.gate import mi

styletrace.init()


@pytest.fixture(scope="module")
def brightness():
    """Each pixel's converged brightness (r+g+b)/3: the physically based render at 256 spp."""
    image = styletrace.render(window_room(), style="identity", spp=256, seed=1, denoise="off")
    u = image.astype(np.float64).mean(axis=2).ravel()
    assert (u > 10).mean() > 0.01  # the window is in the picture and sets the top of the range
    return u


def shares(levels, count):
    return np.bincount(np.asarray(levels).astype(np.int64), minlength=count) / len(levels)


def test_hatching_levels_each_cover_a_fair_share(brightness):
    integrator, chosen = resolve_defaults(
        load_scene(window_room()), make_integrator(style="hatching")
    )
    style = integrator.settings.style
    assert "tones=" in chosen and style.uses_tones
    got = shares(style.active(mi.Float(brightness.astype(np.float32))), style.sets + 1)
    fair = 1.0 / (style.sets + 1)
    assert got.min() >= 0.5 * fair, got  # measured: 0.18, 0.23, 0.32, 0.27
    # the linear ramp between the 5% and 95% quantiles: the room piles into one level (measured
    # 0.61)
    lo, hi = np.quantile(brightness, [0.05, 0.95])
    ramp = make_integrator(style="hatching", u_min=float(lo), u_max=float(hi)).settings.style
    old = shares(ramp.active(mi.Float(brightness.astype(np.float32))), ramp.sets + 1)
    assert old.max() > 0.5 and old.min() < 0.5 * fair, old


def test_cel_bands_each_cover_a_fair_share_and_are_distinct(brightness):
    integrator, _ = resolve_defaults(load_scene(window_room()), make_integrator(style="cel"))
    style = integrator.settings.style
    bands = np.searchsorted(np.asarray(style.steps()), brightness, side="right")
    got = shares(bands, style.band_count)
    assert got.min() >= 0.5 / style.band_count, got
    from styletrace.styles.tone import lightness
    # levels are pinned to 4 significant digits: a relative change of 5e-4 moves L* by at most ~0.02
    assert np.all(np.diff(lightness(style.band_values())) >= 18.0 - 0.05)
    assert max(style.band_values()) < 0.95  # no band at the old fixed 0.95: not washed out
