"""`line_types` (config/line_types.py): the line dictionary of line_mode lifted, parsed with its
defaults and refused in one line where it is wrong or where another mode would ignore it."""
import pytest

from styletrace.config.line_types import LineType, parse_line_types, without_colours
from styletrace.config.settings import parse
from styletrace.errors import SettingsError


def lifted(**kw):
    return parse({"lines": True, "line_mode": "lifted", **kw}).lines


def test_entries_in_priority_order_with_the_line_groups_defaults():
    got = lifted(
        line_types="shape_id color=1,0,0; depth threshold=0.05 stencil=square radius=1.5 count=4",
        line_width=3.0,
        line_samples=6,
        line_color="0.1,0.2,0.3",
    )
    assert got.types == (LineType("shape_id", 0.5, "disk", 1.5, 6, (1.0, 0.0, 0.0), 0),
                         LineType("depth", 0.05, "square", 1.5, 4, (0.1, 0.2, 0.3), 1))
    assert got.describe() == "lines(lifted, depth=1, types=shape_id,depth)"


def test_empty_is_one_shape_id_type():
    assert lifted().types == (LineType("shape_id", 0.5, "disk", 1.0, 8, (0.0, 0.0, 0.0), 0),)
    assert parse_line_types(" ; ", 2.0, 8, (0, 0, 0)) == parse_line_types("", 2.0, 8, (0, 0, 0))


@pytest.mark.parametrize(
    "raw,message",
    [
        (
            "ridges",
            "bad measurement 'ridges' in 'line_types' entry 'ridges': expected one of shape_id, "
            "material_id, "
            "depth, normal",
        ),
        ("depth threshold=0", "bad value '0' for 'line_types depth threshold'"),
        ("normal count=300", "bad value '300' for 'line_types normal count'"),
        (
            "depth radius=1 radius=2",
            "field 'radius' given twice in 'line_types' entry 'depth radius=1 radius=2'",
        ),
        (
            "depth width=2",
            "bad field 'width=2' in 'line_types' entry 'depth width=2': expected key=value",
        ),
        (
            "depth stencil=ring",
            "bad stencil 'ring' in 'line_types' entry 'depth stencil=ring': expected disk or "
            "square",
        ),
        ("shape_id color=red", "bad value 'red' for 'line_types shape_id color'"),
    ],
)
def test_bad_entries_are_refused_in_one_line(raw, message):
    with pytest.raises(SettingsError) as e:
        lifted(line_types=raw)
    assert str(e.value).startswith(message) and "\n" not in str(e.value)


def test_line_types_belong_to_the_lifted_mode():
    with pytest.raises(SettingsError, match="line types are read by line_mode lifted only"):
        parse({"lines": True, "line_types": "depth"})
    with pytest.raises(SettingsError, match="'line_gradient' is not drawn by line_mode lifted"):
        lifted(line_gradient="0,0,0;1,1,1")
    assert lifted(line_objects="box").objects == ("box",)
    assert parse({"lines": False, "line_mode": "lifted", "line_types": "depth"}).lines is None


def test_without_colours_keeps_everything_but_each_entrys_colour():
    raw = "shape_id color=1,0,0; depth threshold=0.05 color=0,1,0 stencil=square ;normal"
    assert without_colours(raw) == "shape_id; depth threshold=0.05 stencil=square; normal"
    types = parse_line_types(without_colours(raw), 2.0, 16, (1.0, 1.0, 1.0))
    assert [t.color for t in types] == [(1.0, 1.0, 1.0)] * 3
    assert [(t.measurement, t.threshold, t.stencil) for t in types] == [
        ("shape_id", 0.5, "disk"), ("depth", 0.05, "square"), ("normal", 0.3, "disk")]
