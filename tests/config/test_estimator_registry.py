"""Unbiased estimators inside the renderer, on the furnace scene where the first-hit radiance is
exact.

Every sphere pixel's first hit has exitant radiance I = rho * E exactly, so g(I) is known. Each
pixel value (spp = 1) is one independent estimate, which gives the standard error directly.
"""
import numpy as np
import pytest
from helpers import furnace
from helpers.furnace import I, z_score

import styletrace
from styletrace.errors import SettingsError
from styletrace.frontends.api import make_integrator
from styletrace.styles import create

RES = 96
Z = 4.0


def estimates(scene, mask, style, estimator, n, seeds, **params):
    return furnace.draws(scene, mask, style, n, seeds, n, estimator=estimator, **params)


def gamma(x, g=2.2):
    return x ** (1 / g)


# g(x, st): the exact value, st the style as rendered (the tone styles' auto exposure resolved on
# the furnace, about 0.18 / 0.53: the estimators must scale the samples, not just the curve, to stay
# unbiased)
CASES = [
    ("gamma", "series", 4, {}, lambda x, st: gamma(st.exposure * x)),
    ("gamma", "series_recursive", 4, {}, lambda x, st: gamma(st.exposure * x)),
    ("gamma", "series_single", 8, {}, lambda x, st: gamma(st.exposure * x)),
    ("gamma", "series", 4, {"exposure": 3.0}, lambda x, st: gamma(3.0 * x)),
    ("exp_tone", "series", 2, {}, lambda x, st: 1 - np.exp(-st.exposure * x)),
    ("reinhard", "series", 2, {}, lambda x, st: st.exposure * x / (1 + st.exposure * x)),
    ("contrast", "affine", 1, {}, lambda x, st: 1.5 * (st.exposure * x - 0.5) + 0.5),
    ("identity", "affine", 1, {}, lambda x, st: x),
    ("sepia", "affine", 1, {}, None),
    ("tie_dye", "ustat", 20, {}, None),
    ("tie_dye", "naive", 4, {}, None),
    ("gamma", "telescoping", 2, {}, lambda x, st: gamma(st.exposure * x)),
]


@pytest.mark.parametrize(
    "style,estimator,n,params,g",
    CASES,
    ids=[f"{c[0]}-{c[1]}" + "".join(f"-{k}={v}" for k, v in c[3].items()) for c in CASES],
)
def test_unbiased_estimator_in_the_renderer(scene, mask, style, estimator, n, params, g):
    vals = estimates(scene, mask, style, estimator, n, 6, **params)
    st = furnace.resolved(scene, style, **params)
    if "exposure" in {p.name for p in st.params}:
        assert st.exposure is not None  # resolved on the furnace (or given)
    if style == "sepia":
        A, b = create("sepia").affine()
        exact = np.array(A) @ I + np.array(b)
    elif style == "tie_dye":
        # unbiased for the fitted polynomial, which is what the estimator claims (the fit error is
        # the style's documented approximation, measured in tests/estimators)
        exact = np.array([st.form().fit(st.exposure * I[None, :])[0]]).ravel()
    else:
        exact = g(I, st)
    assert np.all(np.isfinite(vals))
    z = z_score(vals, exact)
    assert np.all(np.abs(z) < Z), (
        f"{style}/{estimator}: mean {vals.mean(0)} vs exact {exact}, z = {z}"
    )


def sepia(x):
    A, b = create("sepia").affine()
    return np.array(A) @ x + np.array(b)


# the operands' exposures pinned (their auto values are tested above): 1, and 2 for an operand's
# samples scaled inside `combined`
COMPOSED = [  # Fig. 10's combined gu-estimator and compositions with a power-series operand
    ("contrast+sepia", "combined", 1, lambda x: sepia(1.6 * (x - 0.3) + 0.3)),
    ("contrast+sepia", "affine", 1, lambda x: sepia(1.6 * (x - 0.3) + 0.3)),
    ("gamma+sepia", "combined", 4, lambda x: sepia(gamma(2 * x))),
    ("contrast+gamma", "combined", 4, lambda x: gamma(2 * (1.6 * (x - 0.3) + 0.3))),
]


@pytest.mark.parametrize("style,estimator,n,g", COMPOSED, ids=[f"{c[0]}-{c[1]}" for c in COMPOSED])
def test_composed_styles_are_unbiased_in_the_renderer(scene, mask, style, estimator, n, g):
    params = (
        {"contrast.c": 1.6, "contrast.pivot": 0.3, "contrast.exposure": 1.0}
        if style.startswith("contrast")
        else {}
    )
    if "gamma" in style:
        params["gamma.exposure"] = 2.0
    vals = estimates(scene, mask, style, estimator, n, 6, **params)
    assert np.all(np.isfinite(vals))
    z = z_score(vals, g(I))
    assert np.all(np.abs(z) < Z), (
        f"{style}/{estimator}: mean {vals.mean(0)} vs exact {g(I)}, z = {z}"
    )


def test_direct_application_of_a_nonlinear_composition_is_measurably_biased(scene, mask):
    vals = estimates(scene, mask, "gamma+sepia", "direct", 1, 6, **{"gamma.exposure": 1.0})
    z = z_score(vals, sepia(gamma(I)))
    assert np.all(z < -Z), z


def test_direct_with_one_sample_is_measurably_biased(scene, mask):
    vals = estimates(scene, mask, "gamma", "direct", 1, 6, exposure=1.0)
    assert np.all(z_score(vals, gamma(I)) < -Z)


def test_inapplicable_estimator_is_refused():
    with pytest.raises(SettingsError, match="estimator 'series' does not apply to style 'cel'"):
        make_integrator("cel", estimator="series")
    with pytest.raises(SettingsError, match="unknown estimator 'magic'"):
        make_integrator("gamma", estimator="magic")


def test_per_sample_baseline_is_styled_once(scene, mask):
    """acp applies g to every child and averages: E[g(X)] does not depend on n (a second
    application of g to the average would make n = 1 and n = 8 disagree)."""
    one = estimates(scene, mask, "acp", "direct", 1, 6)
    eight = estimates(scene, mask, "acp", "direct", 8, 2)
    se = np.sqrt(one.var(0, ddof=1) / len(one) + eight.var(0, ddof=1) / len(eight))
    z = (one.mean(0) - eight.mean(0)) / se
    assert np.all(np.abs(z) < Z), f"acp means at n=1 {one.mean(0)} and n=8 {eight.mean(0)}: z = {z}"


def test_per_object_estimator(mask):
    """A `styled` BSDF carries its own estimator: the furnace sphere styled with gamma and the
    iterative series estimator, rendered with first_object_hit, is unbiased for I^(1/2.2)."""
    import mitsuba as mi
    d = styletrace.frontends.api.scene_dict("furnace", RES, RES)
    d["sphere"]["bsdf"] = {
        "type": "styled",
        "style": "gamma",
        "estimator": "series",
        "inner_samples": 4,
        "exposure": 1.0,
        "bsdf": d["sphere"]["bsdf"],
    }
    vals = furnace.draws(mi.load_dict(d), mask, "identity", 1, 6, 77, stylize="first_object_hit")
    z = z_score(vals, gamma(I))
    assert np.all(np.abs(z) < Z), f"mean {vals.mean(0)} vs {gamma(I)}: z = {z}"


@pytest.mark.parametrize("estimator", ["series", "series_recursive", "series_single"])
def test_series_estimators_stay_finite_with_fireflies(estimator):
    """In the Cornell box some children hit the light (radiance 18, far outside the convergence
    region about a pilot b ~ 0.3): the estimates get huge, but every pixel stays finite (no inf *
    0 = NaN from an overflowing coefficient, no overflowing products past the renderer's term
    cap)."""
    img = styletrace.render(
        "cornell-box", style="gamma", estimator=estimator, inner=4, spp=4, width=32, height=32
    )
    assert np.isfinite(img).all()
