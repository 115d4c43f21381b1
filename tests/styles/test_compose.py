"""Compositions `a+b+...`: one style applying its operands in order, with prefixed parameters and
forms."""
import numpy as np
import pytest

from styletrace.config import estimator_registry as estimation
from styletrace.config import settings
from styletrace.errors import StyleError
from styletrace.styles import create, style_class, style_names
from styletrace.styles.forms import AffineForm, CompositeForm

from .support import run


def test_applies_its_operands_in_order():
    I = np.random.default_rng(3).uniform(0, 2, size=(40, 3))
    comp = create(
        "contrast+gamma", **{"contrast.c": 1.2, "contrast.pivot": 0.3, "gamma.gamma": 2.0}
    )
    contrast = 1.2 * (I - 0.3) + 0.3
    np.testing.assert_allclose(run(comp, I), np.maximum(contrast, 0) ** 0.5, rtol=2e-6, atol=1e-6)
    # the other order is another function
    other = create(
        "gamma+contrast", **{"contrast.c": 1.2, "contrast.pivot": 0.3, "gamma.gamma": 2.0}
    )
    np.testing.assert_allclose(run(other, I), 1.2 * (I ** 0.5 - 0.3) + 0.3, rtol=2e-6, atol=1e-6)


def test_parameters_are_the_operands_under_their_names():
    cls = style_class("contrast+sepia")
    assert [p.name for p in cls.params] == [
        "contrast.c",
        "contrast.pivot",
        "contrast.exposure",
        "sepia.gradient",
    ]
    comp = create("contrast+sepia", **{"contrast.c": "2"})
    assert comp.operands[0].c == 2.0 and comp.operands[0].pivot == style_class("contrast")().pivot
    assert comp.describe().startswith(
        "contrast+sepia(contrast.c=2, contrast.pivot=auto, contrast.exposure=auto, sepia.gradient="
    )
    assert style_class("contrast+sepia") is cls  # one class per spelling
    assert "contrast+sepia" not in style_names()  # compositions are spelled, not registered


def test_affine_operands_compose_into_one_affine_form():
    comp = create("contrast+sepia", **{"contrast.c": 1.6, "contrast.pivot": 0.3})
    form = comp.form()
    assert isinstance(form, CompositeForm) and isinstance(form.affine, AffineForm)
    I = np.random.default_rng(5).uniform(0, 3, size=(25, 3))
    A, b = np.array(form.affine.a1), np.array(form.affine.a0)
    np.testing.assert_allclose(run(comp, I), I @ A.T + b, rtol=1e-5, atol=1e-6)
    assert estimation.applicable(comp) == ["direct", "affine", "telescoping", "combined"]


def test_estimators_follow_the_operands_forms():
    assert estimation.applicable(create("gamma+sepia")) == ["direct", "telescoping", "combined"]
    assert isinstance(create("gamma+sepia").form(), CompositeForm)
    assert create("gamma+sepia").form().affine is None
    assert estimation.applicable(create("cel+gamma")) == ["direct"]  # cel has no form
    assert create("cel+gamma").form() is None


@pytest.mark.parametrize("name,message", [
    ("contrast+contrast", "each style may appear once"),
    ("acp+gamma", "'acp' cannot be composed"),
    ("contrast+", r"a composition is 'STYLE\+STYLE"),
    ("contrast+nope", "unknown style 'nope'"),
])
def test_bad_compositions_are_one_line(name, message):
    with pytest.raises(StyleError, match=message):
        style_class(name)


def test_bad_operand_parameter_names_both():
    with pytest.raises(
        StyleError, match="bad value -1.0 for parameter 'contrast.c'|bad value -1 for parameter 'c'"
    ):
        create("contrast+sepia", **{"contrast.c": -1.0})
    with pytest.raises(StyleError, match="unknown parameter 'c' for style 'contrast\\+sepia'"):
        create("contrast+sepia", c=1.0)


def test_settings_accept_prefixed_parameters():
    s = settings.parse(
        {
            "style": "contrast+sepia",
            "contrast.c": "1.6",
            "estimator": "combined",
            "inner_samples": 1,
        }
    )
    assert s.style.operands[0].c == 1.6 and s.slot.estimator == "combined"


def test_a_closed_form_first_operand_makes_a_closed_form_composite():
    # contrast acts on gooch's colour, not on radiance
    assert style_class("gooch+contrast").default_inner == 0
    assert style_class("contrast+gooch").default_inner == style_class("contrast").default_inner
    assert style_class("cel+gamma").default_inner == max(
        style_class("cel").default_inner, style_class("gamma").default_inner
    )
