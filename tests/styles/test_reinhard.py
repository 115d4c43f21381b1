import numpy as np

from styletrace.styles import create

from .support import rejects, rejects_unknown, run


def test_hand_values():
    out = run(create("reinhard"), [(0.0, 1.0, 3.0)])
    np.testing.assert_allclose(out, [(0.0, 0.5, 0.75)], atol=1e-6)
    out = run(create("reinhard", white=2.0), [(2.0, 6.0, 0.5)])
    np.testing.assert_allclose(out, [(0.5, 0.75, 0.2)], atol=1e-6)


def test_series_form_matches_the_curve():
    """1 - w/(w + I): the reciprocal series of the shifted samples w + X, scaled and offset."""
    form = create("reinhard", white=2.0).form()
    I = np.linspace(0, 5, 11)
    np.testing.assert_allclose(
        form.scale * form.series.function(I + form.shift) + form.offset, I / (2 + I), rtol=1e-12
    )


def test_parameters():
    rejects("reinhard", "white", 0.0)
    rejects("reinhard", "white", -1)
    rejects_unknown("reinhard")
