"""The firefly control at the stylized vertex (`firefly`, docs/look.md) on a scene with a tiny
bright light that the floor sees only in a mirror: its light arrives as rare, very bright
children (a caustic), which without the control become white specks of contrast's amplified tone
and of the physically based image."""
import numpy as np
import pytest
from helpers.look_scenes import caustic_scene

import styletrace
from styletrace.measures import firefly_share

styletrace.init()


@pytest.mark.parametrize("style", ["contrast", "identity"])
def test_the_control_removes_the_specks_of_rare_bright_children(style):
    """Measured at 64 x 64 (seed 1): contrast 2.7% -> 0.27% of the pixels, identity 2.3% ->
    0.34%. Here the control must remove at least three quarters of them, on three seeds together."""
    def share(firefly):
        return np.mean(
            [
                firefly_share(
                    styletrace.render(
                        caustic_scene(),
                        style=style,
                        inner=16,
                        spp=4,
                        seed=s,
                        denoise="off",
                        firefly=firefly,
                    )
                )
                for s in range(3)
            ]
        )
    without, with_control = share(0), share(4)
    assert without > 0.01, without  # the scene does make fireflies (else this tests nothing)
    assert with_control < 0.25 * without, (with_control, without)


def test_off_is_the_papers_estimator_and_auto_is_off_without_denoising():
    # a box filter: a gaussian's film adds its samples with atomics, in no fixed order (last-bit
    # differences)
    a = styletrace.render(
        caustic_scene(16, "box"), style="contrast", inner=4, spp=2, seed=0, denoise="off"
    )
    b = styletrace.render(
        caustic_scene(16, "box"), style="contrast", inner=4, spp=2, seed=0, denoise="off", firefly=0
    )
    assert np.array_equal(a, b)


def test_a_buffer_keeps_the_controlled_mean_so_restyles_equal_renders():
    kw = dict(style="contrast", inner=8, spp=2, seed=4, firefly=4)
    buf = styletrace.render_buffer(caustic_scene(24), **kw)
    image = styletrace.render(caustic_scene(24), denoise="off", **kw)
    # the recording kernel has more outputs (the filtered buffer's positions): equal up to float
    # rounding
    np.testing.assert_allclose(buf.image, image, rtol=1e-5, atol=1e-6)
    np.testing.assert_allclose(
        styletrace.restyle(buf, style="contrast"), image, rtol=1e-5, atol=1e-5
    )


def test_a_bad_k_is_refused_in_one_line():
    with pytest.raises(styletrace.errors.SettingsError, match=r"bad value 0.5 for 'firefly'"):
        styletrace.render(caustic_scene(8), style="cel", spp=1, firefly=0.5, denoise="off")
