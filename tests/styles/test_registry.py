"""Every registered style: metadata, parameter round trips, and one kernel evaluation."""
import numpy as np
import pytest

from styletrace.styles import Style, StyleError, create, style_class, style_names

from .support import run, vertex

EXPECTED = [
    "acp",
    "cel",
    "color_map",
    "contrast",
    "gamma",
    "gooch",
    "halftone",
    "hatching",
    "identity",
    "saturation",
    "sepia",
    "tie_dye",
    "xtoon",
]


ALL = style_names()


def test_all_styles_registered():
    assert set(EXPECTED) <= set(ALL)


def test_unknown_style():
    with pytest.raises(StyleError, match="unknown style 'nope'.*gooch"):
        style_class("nope")


@pytest.mark.parametrize("name", ALL)
def test_metadata_and_round_trip(name):
    cls = style_class(name)
    assert issubclass(cls, Style) and cls.name == name and cls.summary and cls.default_inner >= 0
    assert cls.__module__.rsplit(".", 1)[1] == name
    style = create(name)
    # describe() prints every parameter in a form parse() reads back to the same style
    again = create(name, **{p.name: p.show(style.values[p.name]) for p in cls.params})
    assert again.describe() == style.describe()
    assert (cls.default_inner == 0) == style.closed_form


@pytest.mark.parametrize("name", ALL)
def test_apply_is_finite_on_mixed_inputs(name):
    rng = np.random.default_rng(11)
    I = np.concatenate([rng.uniform(-0.5, 5, size=(30, 3)), np.zeros((2, 3)), np.full((2, 3), 0.3)])
    n = rng.normal(size=(34, 3))
    wo = rng.normal(size=(34, 3))
    wo /= np.linalg.norm(wo, axis=1, keepdims=True)
    out = run(create(name), I, vertex(p=rng.uniform(-1, 1, size=(34, 3)) + [0, 0, 3], n=n, wo=wo))
    assert out.shape == (34, 3) and np.all(np.isfinite(out))
