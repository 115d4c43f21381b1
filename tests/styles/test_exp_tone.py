import math

import numpy as np

from styletrace.styles import create

from .support import rejects, rejects_unknown, run


def test_hand_values():
    # 1 - exp(-k x) with k = ln 2: 0 -> 0, 1 -> 1/2, 2 -> 3/4, 3 -> 7/8
    out = run(create("exp_tone", exposure=math.log(2)), [(0.0, 1.0, 2.0), (3.0, 1.0, 0.0)])
    np.testing.assert_allclose(out, [(0.0, 0.5, 0.75), (0.875, 0.5, 0.0)], atol=1e-6)


def test_series_form_matches_the_curve():
    """The series the unbiased estimators expand is the same function: 1 - a^I with a = e^-k."""
    style = create("exp_tone", exposure=1.5)
    form = style.form()
    I = np.linspace(0, 3, 7)
    np.testing.assert_allclose(
        form.scale * form.series.function(I) + form.offset, 1 - np.exp(-1.5 * I), rtol=1e-12
    )


def test_parameters():
    rejects("exp_tone", "exposure", 0.0)
    rejects("exp_tone", "exposure", "fast")
    rejects_unknown("exp_tone")
