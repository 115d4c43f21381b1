"""The tone curve and cel's levels from a brightness distribution (`styles.tone`): equal shares,
lightness steps."""
import numpy as np
import pytest

from styletrace.styles import create
from styletrace.styles.tone import (
    LSTAR_RANGE,
    MIN_STEP_LSTAR,
    band_levels,
    lightness,
    luminance_of,
    tone_inverse,
    tone_knots,
)


def quantile_of(values):
    return lambda qs: list(np.quantile(values, qs))


#: a room at ~0.05 with a window at ~20 on 30% of the image: the case where a linear ramp fails
ROOM = np.concatenate([np.random.default_rng(0).lognormal(np.log(0.05), 0.8, 7000),
                       np.random.default_rng(1).lognormal(np.log(20.0), 0.3, 3000)])


def test_lightness_round_trips():
    y = np.array([0.0, 0.001, 0.008856, 0.18, 0.5, 1.0])
    np.testing.assert_allclose(luminance_of(lightness(y)), y, atol=1e-12)
    assert lightness(0.18) == pytest.approx(49.5, abs=0.05) and lightness(1.0) == pytest.approx(
        100.0
    )


def test_knots_give_every_level_a_fair_share_where_a_linear_ramp_does_not():
    knots = tone_knots(quantile_of(ROOM))
    assert all(b > a for a, b in zip(knots, knots[1:]))
    h = create("hatching", tones=",".join(f"{k:.6g}" for k in knots))
    import mitsuba as mi

    import styletrace
    styletrace.init()
    u = mi.Float(ROOM.astype(np.float32))
    levels = np.asarray(h.active(u)).astype(int)
    shares = np.bincount(levels, minlength=4) / len(ROOM)
    assert shares.min() > 0.5 * 0.25, shares  # each of the 4 levels at least half its fair share
    lin = create(
        "hatching", u_min=float(np.quantile(ROOM, 0.05)), u_max=float(np.quantile(ROOM, 0.95))
    )
    shares_lin = np.bincount(np.asarray(lin.active(u)).astype(int), minlength=4) / len(ROOM)
    assert shares_lin.max() > 0.6, shares_lin  # the room falls into the darkest level


def test_tone_inverse_inverts_the_curve():
    knots = tone_knots(quantile_of(ROOM))
    for f in (0.0, 0.1, 0.5, 0.77, 1.0):
        u = tone_inverse(f, knots)
        assert np.interp(u, knots, np.linspace(0, 1, len(knots))) == pytest.approx(f, abs=1e-9)


@pytest.mark.parametrize("bands", [2, 3, 4, 6])
def test_cel_levels_are_distinct_and_displayable(bands):
    for values in (ROOM, np.random.default_rng(2).normal(0.5, 0.01, 5000), ROOM * 1e-3):
        levels = band_levels(quantile_of(values), bands)
        lstar = lightness(levels)
        assert np.all(
            np.diff(lstar)
            >= min(MIN_STEP_LSTAR, (LSTAR_RANGE[1] - LSTAR_RANGE[0]) / (bands - 1)) - 1e-6
        )
        assert LSTAR_RANGE[0] - 1e-6 <= lstar.min() and lstar.max() <= LSTAR_RANGE[1] + 1e-6


def test_levels_follow_exposure_not_absolute_brightness():
    """A scene and the same scene a thousand times dimmer get the same levels (the median is
    middle grey)."""
    np.testing.assert_allclose(
        band_levels(quantile_of(ROOM), 3), band_levels(quantile_of(ROOM * 1e-3), 3), rtol=1e-9
    )


def test_given_values_win_and_tones_exclude_a_linear_ramp():
    from styletrace.errors import StyleError
    assert create("hatching", u_min=0.1).uses_tones is False
    with pytest.raises(StyleError, match="tones and u_min/u_max are alternatives"):
        create("hatching", tones="0.1,0.2,0.3", u_max=1.0)
    with pytest.raises(StyleError, match="must not decrease"):
        create("halftone", tones="0.3,0.2")
