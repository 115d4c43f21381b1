"""A property is declared once (config/declare.py): one `settings.declare(Property(...))` gives
its command-line flag, its row in the docs table, its parsing (type, bounds, choices, one-line
errors) from every front end (the CLI, Python values, Mitsuba properties), and its value on the
parsed `Settings`."""
import pytest

from styletrace.config import settings
from styletrace.config.declare import Property
from styletrace.errors import SettingsError
from styletrace.frontends.cli import build_parser
from styletrace.frontends.command_job import given_flags
from styletrace.frontends.reference import integrator_table
from styletrace.gate import mi
from styletrace.kernel.integrator import StylizedIntegrator

KNOB = Property(
    "test_knob", 3, "int", "a knob only this test has", "--test-knob", "K", low=1, high=9
)
MODE = Property(
    "test_mode", "soft", "string", "a choice only this test has", choices=("soft", "hard")
)


@pytest.fixture
def declared(monkeypatch):
    """The two properties declared, and the table as it was afterwards."""
    monkeypatch.setattr(settings, "PROPERTIES", settings.PROPERTIES)
    monkeypatch.setattr(settings, "DEFAULTS", dict(settings.DEFAULTS))
    settings.declare(KNOB)
    settings.declare(MODE)


def test_its_flag(declared, capsys):
    args = build_parser().parse_args(["render", "cornell-box", "--test-knob", "5"])
    assert given_flags(args, {}) == {"test_knob": 5}
    with pytest.raises(SystemExit):
        build_parser().parse_args(["render", "--help"])
    assert "a knob only this test has (default: 3)" in " ".join(capsys.readouterr().out.split())


def test_its_docs_row(declared):
    rows = integrator_table().splitlines()
    assert "| `test_knob` | int | `3` | `--test-knob` | a knob only this test has |" in rows
    assert "| `test_mode` | string | `soft` |  | a choice only this test has |" in rows


def test_its_parsing_from_every_front_end(declared):
    assert settings.parse({}).test_knob == 3 and settings.parse({}).test_mode == "soft"
    assert settings.parse({"test_knob": "7", "test_mode": "hard"}).test_knob == 7
    assert StylizedIntegrator.from_values({"test_knob": 8}).settings.test_knob == 8
    assert (
        mi.load_dict({"type": "stylized", "test_knob": 4, "test_mode": "hard"}).settings.test_mode
        == "hard"
    )
    with pytest.raises(
        SettingsError, match=r"^bad value '0' for 'test_knob': expected an integer in \[1, 9\]$"
    ):
        settings.parse({"test_knob": "0"})
    with pytest.raises(
        SettingsError, match=r"^bad value 'odd' for 'test_mode': expected one of soft, hard$"
    ):
        settings.parse({"test_mode": "odd"})


def test_undeclared_it_is_unknown():
    with pytest.raises(SettingsError, match="unknown property 'test_knob'"):
        settings.parse({"test_knob": 5})
    assert all(p.name != "test_knob" for p in settings.PROPERTIES)


def test_declaring_a_name_twice_is_refused(declared):
    with pytest.raises(ValueError, match="declared already"):
        settings.declare(KNOB)


def test_the_built_in_properties_parse_by_their_declaration():
    """The bounds live in the declaration: parse refuses what the declaration refuses, with its
    message."""
    for prop in settings.PROPERTIES:
        if prop.kind == "int" and prop.low is not None:
            with pytest.raises(SettingsError, match=f"for '{prop.name}': expected an integer in"):
                prop.parse(int(prop.low) - 1)
        if prop.choices:
            assert prop.parse(prop.default) == prop.default
    with pytest.raises(SettingsError, match=r"'rr_depth': expected an integer in \[1, "):
        settings.parse({"rr_depth": 0})
