"""One class declares every setting (styletrace/declaration.py): an integrator property
(config/declare.py's `Property`) and a style parameter (styles/params.py's `Param`) are both a
`Declaration`, parsed by its one implementation of the common kinds, and each gives its type,
default, bounds, choices, doc line and its command-line / docs row."""
import pytest

from styletrace.config import settings
from styletrace.config.declare import Property
from styletrace.declaration import Declaration
from styletrace.errors import SettingsError, StyleError
from styletrace.frontends.cli import build_parser, main
from styletrace.frontends.command_job import given_flags
from styletrace.frontends.reference import integrator_table, style_table
from styletrace.styles import style_class
from styletrace.styles.params import Param

KNOB = Property(
    "test_knob", 3, "int", "a knob only this test has", "--test-knob", "K", low=1, high=9
)
AMOUNT = Param(
    "test_amount", "float", 0.5, "an amount only this test has", low=0.0, high=1.0, low_open=True
)
MODE = Param("test_mode", "choice", "soft", "a choice only this test has", choices=("soft", "hard"))


@pytest.fixture
def declared(monkeypatch):
    monkeypatch.setattr(settings, "PROPERTIES", settings.PROPERTIES)
    monkeypatch.setattr(settings, "DEFAULTS", dict(settings.DEFAULTS))
    settings.declare(KNOB)
    sepia = style_class("sepia")
    monkeypatch.setattr(sepia, "params", tuple(sepia.params) + (AMOUNT, MODE))


def test_one_class_declares_both():
    for d in (KNOB, AMOUNT, MODE):
        assert isinstance(d, Declaration)
    # Param.parse only adds 'auto' before Declaration.parse
    assert "parse" not in vars(Property)
    # type, default, bounds, choices and doc line, read the same way on both sides
    assert (KNOB.kind, KNOB.default, KNOB.bounds(), KNOB.choices, KNOB.doc) == \
        ("int", 3, (1, 9), (), "a knob only this test has")
    assert (AMOUNT.kind, AMOUNT.default, AMOUNT.bounds(), AMOUNT.low_open, AMOUNT.doc) == \
        ("float", 0.5, (0.0, 1.0), True, "an amount only this test has")
    assert (MODE.kind, MODE.choices) == ("choice", ("soft", "hard"))


def test_the_common_kinds_parse_once_with_each_sides_message():
    assert (
        KNOB.parse(" 7 ") == 7 and AMOUNT.parse("0.25") == 0.25 and MODE.parse(" hard ") == "hard"
    )
    with pytest.raises(
        SettingsError, match=r"^bad value '0' for 'test_knob': expected an integer in \[1, 9\]$"
    ):
        KNOB.parse("0")
    with pytest.raises(
        StyleError,
        match=r"^bad value 0 for parameter 'test_amount': expected a number in "
        r"\(0, 1\]$",
    ):
        AMOUNT.parse(0)
    with pytest.raises(
        StyleError,
        match=r"^bad value 'odd' for parameter 'test_mode': expected one of soft, "
        r"hard$",
    ):
        MODE.parse("odd")
    # the sides' spellings are declared options of one parser, kept as they were
    flag = Property("test_flag", False, "bool", "")
    switch = Param("test_switch", "bool", False, "")
    assert switch.parse("on") is True and switch.parse("no") is False
    with pytest.raises(SettingsError, match="expected true or false"):
        flag.parse("on")
    assert Param("n", "int", 1, "").parse(True) == 1
    with pytest.raises(SettingsError, match="expected an integer"):
        Property("n", 1, "int", "").parse(True)
    assert Param("c", "color", (1, 1, 1), "").parse("#ff0000") == (1.0, 0.0, 0.0)
    assert Property("c", (1, 1, 1), "rgb", "").parse("1,0,0") == (1.0, 0.0, 0.0)
    with pytest.raises(SettingsError, match=r"expected a colour r,g,b \(three numbers >= 0\)"):
        Property("c", (1, 1, 1), "rgb", "").parse("-1,0,0")


def test_each_gives_its_cli_and_docs_row(declared, capsys):
    args = build_parser().parse_args(["render", "cornell-box", "--test-knob", "5"])
    assert given_flags(args, {}) == {"test_knob": 5}
    assert (
        "| `test_knob` | int | `3` | `--test-knob` | a knob only this test has |"
        in integrator_table().splitlines()
    )
    rows = style_table("sepia").splitlines()
    assert (
        "| test_amount | float | `0.5` | an amount only this test has | a number in (0, 1] |"
        in rows
    )
    assert (
        "| test_mode | choice | `soft` | a choice only this test has | one of soft, hard |" in rows
    )
    assert main(["styles"]) == 0
    out = capsys.readouterr().out
    assert "    test_amount = 0.5    an amount only this test has; a number in (0, 1]" in out
    assert "    test_mode = soft    a choice only this test has; one of soft, hard" in out
