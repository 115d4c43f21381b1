"""Typed parameters: every real value finite and within its range, once, for every style."""
import math

import numpy as np
import pytest

from styletrace.styles import StyleError, create, style_class, style_names
from styletrace.styles.gradient import Gradient
from styletrace.styles.params import LIMIT, Param


@pytest.mark.parametrize(
    "kind,value",
    [
        ("float", math.inf),
        ("float", -math.inf),
        ("float", math.nan),
        ("float", 1e300),
        ("color", "inf,0,0"),
        ("color", (0.0, math.nan, 0.0)),
        ("vector", "0,1e300,0"),
        ("floats", "1,inf"),
        ("int", "1e400"),
        ("int", math.inf),
    ],
)
def test_reals_are_finite_and_bounded_by_default(kind, value):
    p = Param("x", kind, None, "test")
    with pytest.raises(StyleError, match="bad value .* for parameter 'x'"):
        p.parse(value)


def test_the_default_bound_is_in_the_allowed_text():
    assert Param("x", "float", 0.0, "").allowed() == "a number in [-1e+06, 1e+06]"
    assert (
        Param("x", "float", 1.0, "", low=0.0, low_open=True).allowed() == "a number in (0, 1e+06]"
    )
    assert Param("x", "color", (0, 0, 0), "", low=0.0).allowed() == \
        "an RGB colour: 'r,g,b' with each value in [0, 1e+06], or '#rrggbb'"
    assert Param("x", "float", 1.0, "").parse(LIMIT) == LIMIT
    # a product of two parameters and a radiance of 1e20 stays finite in float32
    assert np.isfinite(np.float32(LIMIT) * np.float32(LIMIT) * np.float32(1e20))


@pytest.mark.parametrize(
    "spec",
    [
        "0:#000000;nan:#ffffff",
        "0:#000000;inf:#ffffff",
        "0:#000000;1e-40:#ffffff",
        "1:#000000;1.00000001:#ffffff",
    ],
)
def test_gradient_stops_are_finite_and_distinct_in_float32(spec):
    with pytest.raises(StyleError, match="finite positions that strictly increase"):
        Gradient.parse(spec)


def test_gradient_colours_are_bounded():
    with pytest.raises(StyleError, match="must be finite numbers"):
        create("color_map", gradient="0:#000000;1:inf,0,0")


@pytest.mark.parametrize(
    "style,param,value",
    [
        ("exp_tone", "exposure", 87.01),
        ("reinhard", "white", 1000.5),
        ("gamma", "gamma", 0.099),
        ("tie_dye", "phases", 1e30),
    ],
)
def test_formula_bounds(style, param, value):
    with pytest.raises(StyleError, match=f"parameter '{param}'"):
        create(style, **{param: value})


def test_tie_dye_keeps_the_cosine_argument_resolvable():
    # pi*100*50 < 2^14
    create("tie_dye", frequencies=100.0, phases=0.0, domain_min=-1.0, domain_max=50.0)
    with pytest.raises(StyleError, match="must stay below 16384"):
        create("tie_dye", frequencies=100.0, phases=0.0, domain_min=-1.0, domain_max=60.0)


def test_every_real_parameter_has_a_finite_range():
    for name in style_names():
        for p in style_class(name).params:
            if p.kind in ("float", "color", "vector", "floats"):
                lo, hi = p.bounds()
                assert math.isfinite(lo) and math.isfinite(hi), (name, p.name)
