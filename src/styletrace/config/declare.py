"""One declaration per integrator property: type, default, bounds, choices, doc line, CLI flag.

    Property("line_k", 12, "int", "expectation mode: k, the opacity control", low=1, high=256)

`Property` is the integrator's side of `styletrace.declaration.Declaration`: the command line makes
its flag from it, the docs their table row, `settings.parse` its value. Also here: the shared value
parsers (integer, number, boolean, names, rgb), each failing with one line naming the value and
what is allowed. Rationale: docs/design/declarations.md.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Any, ClassVar

from styletrace.declaration import Declaration
from styletrace.errors import SettingsError

#: Largest depth or count: the kernel counts depths and samples in UInt32, and 2^32 - 1 stands for
#: "unbounded" (`path.depth_limit`), so larger values would wrap around.
COUNT_MAX = 2 ** 32 - 2

def integer(key: str, raw: Any, low: int, high: int = COUNT_MAX) -> int:
    """An integer in [low, high] from a number or a string, exact: 1.5 and '2.7' are refused.

    Args:
        key: the setting's name, as the error names it.
        raw: an int, an integral float or a string; True/False are refused.
        low, high: the inclusive bounds (high: COUNT_MAX unless given).

    Returns:
        The integer.

    Raises:
        SettingsError: not an exact integer, or out of bounds.
    """
    return Property(key, None, "int", "", low=low, high=high).parse(raw)


def number(key: str, raw: Any, low: float, high: float = float("inf"),
           low_open: bool = False) -> float:
    """A finite float in [low, high] (or (low, high] with `low_open`) from a number or a string.

    Args:
        key: the setting's name, as the error names it.
        raw: a number or a string; True/False are refused.
        low, high: the bounds (high: unbounded unless given); low_open: exclude `low` itself.

    Returns:
        The float.

    Raises:
        SettingsError: not a number, or outside the bounds (NaN always is).
    """
    return Property(key, None, "float", "", low=low, high=high, low_open=low_open).parse(raw)


def parse_names(key: str, raw: Any) -> tuple[str, ...]:
    """A list of names from 'a,b' or a list/tuple of strings.

    Args:
        key: the setting's name, as the error names it.
        raw: 'a,b' (comma-separated) or a list or tuple; names are stripped, empty ones dropped.

    Returns:
        The names.

    Raises:
        SettingsError: `raw` is neither a string nor a list or tuple.
    """
    return Property(key, None, "list", "").parse(raw)


def rgb(key: str, raw: Any) -> tuple[float, float, float]:
    """An RGB colour from 'r,g,b', a list of three numbers, or one grey number.

    Args:
        key: the setting's name, as the error names it.
        raw: 'r,g,b', a sequence of three numbers, or one number (grey); each component >= 0.

    Returns:
        (r, g, b) floats.

    Raises:
        SettingsError: not three numbers, or a component below 0.
    """
    return Property(key, None, "rgb", "").parse(raw)


def boolean(key: str, raw: Any) -> bool:
    """A bool from True/False, 1/0 or the strings 'true'/'false'/'1'/'0' (any case).

    Args:
        key: the setting's name, as the error names it.
        raw: a bool, an int 1/0, or one of those strings (a float is refused).

    Returns:
        The bool.

    Raises:
        SettingsError: any other value.
    """
    return Property(key, None, "bool", "").parse(raw)


@dataclass(frozen=True, init=False)
class Property(Declaration):
    """One integrator property (see the module doc): a `Declaration` with its command-line flag.
    Spellings: bool is true/false/1/0; an int or float is never True/False; an rgb is 'r,g,b' >= 0.

    Args:
        name, default, doc: the property's name, default value, and its docs' line.
        kind: int | float | bool | string | list | rgb | the docs' wording for the few parsed in
            `settings.parse` (int or list).
        flag, metavar: the `styletrace render` flag, if it has its own, and its value's name.
        bare: the flag is a switch without a value (`--lines`).
        low, high: bound a number (None: unbounded); low_open: the low end excluded.
        choices: the strings a `string` accepts (none: any string).

    Takes more than 7 parameters: it is a declaration, and each argument is one of its declared
    attributes (the fields above and `Declaration`'s).
    """

    flag: str = ""            # the `styletrace render` flag, if it has its own
    metavar: str = ""
    bare: bool = False        # the flag is a switch without a value (`--lines`)

    OTHER_KIND: ClassVar[str] = "choice"

    def __init__(
        self,
        name: str,
        default: Any,
        kind: str,
        doc: str,
        flag: str = "",
        metavar: str = "",
        bare: bool = False,
        low: float | None = None,
        high: float | None = None,
        low_open: bool = False,
        choices: tuple[str, ...] = (),
    ):
        Declaration.__init__(self, name, kind, default, doc, low, high, low_open, tuple(choices))
        object.__setattr__(self, "flag", flag)
        object.__setattr__(self, "metavar", metavar)
        object.__setattr__(self, "bare", bare)

    def show_default(self) -> str:
        """The default as the docs show it: None is the style's own count (inner_samples) or
        auto; an empty string is none."""
        if self.default is None:
            return "style's" if self.name == "inner_samples" else "auto"
        return "none" if self.default == "" else str(self.default)

    def bounds(self) -> tuple[float, float]:
        if self.kind == "int":
            return (-COUNT_MAX if self.low is None else int(self.low),
                    COUNT_MAX if self.high is None else int(self.high))
        if self.kind == "rgb":
            return (0.0, float("inf"))
        return super().bounds()

    def allowed(self) -> str:
        """What the property accepts, as its errors say it."""
        lo, hi = self.bounds()
        if self.kind == "int":
            return f"an integer in [{lo}, {hi}]"
        if self.kind == "float":
            return f"a number in {'(' if self.low_open else '['}{lo:g}, {hi:g}]"
        if self.kind == "bool":
            return "true or false"
        if self.kind == "list":
            return "a comma-separated list of names"
        if self.kind == "rgb":
            return "a colour r,g,b (three numbers >= 0)"
        return "one of " + ", ".join(self.choices) if self.choices else "a string"

    def fail(self, raw: Any) -> SettingsError:
        shown = raw if self.kind in ("int", "float", "bool", "list", "rgb") else str(raw)
        return SettingsError(f"bad value {shown!r} for '{self.name}': expected {self.allowed()}")

    def convert(self, raw: Any) -> Any:
        if self.kind == "list":
            parts = (raw.split(",") if isinstance(raw, str)
                     else list(raw) if isinstance(raw, (list, tuple)) else None)
            if parts is None:
                raise self.fail(raw)
            return tuple(str(p).strip() for p in parts if str(p).strip())
        return super().convert(raw)


__all__ = ["Property", "COUNT_MAX", "integer", "number", "boolean", "parse_names", "rgb"]
