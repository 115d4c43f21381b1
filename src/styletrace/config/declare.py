"""One declaration per integrator property: type, default, bounds, choices, doc line, CLI flag and docs row.

    Property("line_k", 12, "int", "expectation mode: k, the opacity control", low=1, high=256)

A `Property` is everything the project knows about one setting of the `stylized` integrator: the command
line makes its flag from it (`cli.add_setting_flags`), the docs their table row (`reference.integrator_table`),
and `settings.parse` its value (`Property.parse`: the kind, the bounds and the choices declared here), so
adding a property is one declaration in `settings.PROPERTIES` (or `settings.declare(...)`). Properties whose
value depends on others (inner_samples and stylize_depth, the reuse family, lines) keep their cross-checks
in `settings.parse`; their single values are still parsed here. Also here: the value parsers every front end
shares (integer, number, boolean, names, rgb), each failing with one line naming the value and what is allowed.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from ..errors import SettingsError

#: Largest depth or count: the kernel counts depths and samples in UInt32, and 2^32 - 1 stands for
#: "unbounded" (`path.depth_limit`), so larger values would wrap around.
COUNT_MAX = 2 ** 32 - 2

def integer(key: str, raw: Any, low: int, high: int = COUNT_MAX) -> int:
    """An integer in [low, high] from a number or a string; exact (1.5 and '2.7' are refused, not truncated)."""
    expected = f"expected an integer in [{low}, {high}]"
    try:
        if isinstance(raw, bool):
            raise ValueError
        if isinstance(raw, float) and not raw.is_integer():
            raise ValueError
        value = int(raw.strip()) if isinstance(raw, str) else int(raw)
    except (TypeError, ValueError, OverflowError):
        raise SettingsError(f"bad value {raw!r} for '{key}': {expected}") from None
    if not low <= value <= high:
        raise SettingsError(f"bad value {raw!r} for '{key}': {expected}")
    return value


def number(key: str, raw: Any, low: float, high: float = float("inf"), low_open: bool = False) -> float:
    """A finite float in [low, high] (or (low, high] with `low_open`) from a number or a string."""
    expected = f"expected a number in {'(' if low_open else '['}{low:g}, {high:g}]"
    try:
        if isinstance(raw, bool):
            raise ValueError
        value = float(raw.strip()) if isinstance(raw, str) else float(raw)
    except (TypeError, ValueError, OverflowError):
        raise SettingsError(f"bad value {raw!r} for '{key}': {expected}") from None
    if value != value or not (low < value if low_open else low <= value) or not value <= high:
        raise SettingsError(f"bad value {raw!r} for '{key}': {expected}")
    return value


def names(key: str, raw: Any) -> tuple[str, ...]:
    """A list of names from 'a,b' or a list/tuple of strings."""
    parts = raw.split(",") if isinstance(raw, str) else list(raw) if isinstance(raw, (list, tuple)) else None
    if parts is None:
        raise SettingsError(f"bad value {raw!r} for '{key}': expected a comma-separated list of names")
    return tuple(str(p).strip() for p in parts if str(p).strip())


def rgb(key: str, raw: Any) -> tuple[float, float, float]:
    """An RGB colour from 'r,g,b', a list of three numbers, or one grey number."""
    parts = raw.split(",") if isinstance(raw, str) else list(raw) if isinstance(raw, (list, tuple)) else [raw]
    if len(parts) == 1:
        parts = parts * 3
    if len(parts) != 3:
        raise SettingsError(f"bad value {raw!r} for '{key}': expected a colour r,g,b (three numbers >= 0)")
    try:
        return tuple(number(key, p, 0.0) for p in parts)
    except SettingsError:
        raise SettingsError(f"bad value {raw!r} for '{key}': expected a colour r,g,b (three numbers >= 0)") from None


def boolean(key: str, raw: Any) -> bool:
    """A bool from True/False, 1/0 or the strings 'true'/'false'/'1'/'0' (any case)."""
    text = str(raw).strip().lower()
    if isinstance(raw, bool) or text in ("true", "false", "1", "0") and not isinstance(raw, float):
        return text in ("true", "1")
    raise SettingsError(f"bad value {raw!r} for '{key}': expected true or false")


@dataclass(frozen=True)
class Property:
    """One integrator property (see the module doc). `kind`: int | float | bool | string | list | rgb | the
    docs' wording for the few parsed in `settings.parse` (int or list); `low`/`high` bound a number (`low_open`:
    the low end excluded); `choices`: the strings a `string` accepts."""

    name: str
    default: Any
    kind: str
    doc: str
    flag: str = ""            # the `styletrace render` flag, if it has its own
    metavar: str = ""
    bare: bool = False        # the flag is a switch without a value (`--lines`)
    low: float | None = None
    high: float | None = None
    low_open: bool = False
    choices: tuple[str, ...] = ()

    def show_default(self) -> str:
        return "style's" if self.default is None else str(self.default)

    def parse(self, raw: Any) -> Any:
        """The value `raw` (a CLI string, a Mitsuba property, a Python value) as this property declares it."""
        kind, name = self.kind, self.name
        if kind == "int":
            return integer(name, raw, int(self.low if self.low is not None else -COUNT_MAX),
                           int(self.high if self.high is not None else COUNT_MAX))
        if kind == "float":
            return number(name, raw, self.low if self.low is not None else -float("inf"),
                          self.high if self.high is not None else float("inf"), self.low_open)
        if kind == "bool":
            return boolean(name, raw)
        if kind == "list":
            return names(name, raw)
        if kind == "rgb":
            return rgb(name, raw)
        value = str(raw)
        if self.choices and value not in self.choices:
            raise SettingsError(f"bad value {value!r} for '{name}': expected one of {', '.join(self.choices)}")
        return value


__all__ = ["Property", "COUNT_MAX", "integer", "number", "boolean", "names", "rgb"]
