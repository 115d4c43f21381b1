"""One declaration per setting, for the integrator's properties and the styles' parameters alike.

    Declaration(name, kind, default, doc, low=..., high=..., low_open=..., choices=...)

A `Declaration` holds a setting's kind, default, bounds, choices and doc line, and parses the
common kinds (`parse`): int (exact), float (finite, in bounds), bool, a choice, an RGB triple.
Subclasses: `config.declare.Property` (SettingsError) and `styles.params.Param` (StyleError); a
spelling one side accepts and the other does not is a class attribute of the subclass.
Rationale: docs/design/declarations.md.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, ClassVar

from styletrace.errors import StyletraceError

#: the kind names of both sides, mapped to the common kinds parsed here
COMMON_KINDS = {
    "int": "int",
    "float": "float",
    "bool": "bool",
    "choice": "choice",
    "string": "choice",
    "rgb": "rgb",
    "color": "rgb",
}


@dataclass(frozen=True)
class Declaration:
    """One setting (see the module doc): `low`/`high` bound a number (or each component of a
    colour); `low_open`: the low end excluded; `choices`: the strings a choice accepts (none: any
    string)."""

    name: str
    kind: str
    default: Any
    doc: str
    low: float | None = None
    high: float | None = None
    low_open: bool = False
    choices: tuple[str, ...] = ()

    # The spellings a side accepts (declared options of the subclass):
    TRUE: ClassVar[tuple[str, ...]] = ("true", "1")          # a bool's words (any case)
    FALSE: ClassVar[tuple[str, ...]] = ("false", "0")
    BOOL_IS_NUMBER: ClassVar[bool] = False                    # True/False may stand for 1/0 in an int or float
    STRIP_CHOICE: ClassVar[bool] = False                      # ' soft ' is the choice 'soft'
    OTHER_KIND: ClassVar[str | None] = None                   # the common kind that a kind not named parses as

    # What a side supplies:
    def fail(self, raw: Any) -> StyletraceError:
        """The one-line error for the bad value `raw`."""
        raise NotImplementedError

    def bounds(self) -> tuple[float, float]:
        """The closed range of admissible values (of each component of a colour)."""
        return (-math.inf if self.low is None else self.low, math.inf if self.high is None else self.high)

    def colour_text(self, text: str) -> list[Any]:
        """The components of a colour written as text."""
        return text.split(",")

    def is_sequence(self, raw: Any) -> bool:
        return isinstance(raw, (list, tuple))

    # The one parsing of the common kinds:
    def parse(self, raw: Any) -> Any:
        """The value `raw` (a CLI string, a Mitsuba property, a Python value) as this setting
        declares it."""
        try:
            return self.convert(raw)
        except StyletraceError:
            raise
        except (TypeError, ValueError, IndexError, OverflowError) as exc:
            raise self.fail(raw) from exc

    def convert(self, raw: Any) -> Any:
        """The common kinds; a subclass handles its own kinds and hands the rest here."""
        kind = COMMON_KINDS.get(self.kind, self.OTHER_KIND)
        if kind == "int":
            return self.check(self.integer(raw), raw)
        if kind == "float":
            return self.check(self.real(raw), raw)
        if kind == "bool":
            return self.boolean(raw)
        if kind == "choice":
            value = str(raw).strip() if self.STRIP_CHOICE else str(raw)
            if self.choices and value not in self.choices:
                raise self.fail(raw)
            return value
        if kind == "rgb":
            return self.triple(raw)
        raise AssertionError(f"unknown kind {self.kind!r} of {self.name!r}")

    def check(self, x: Any, raw: Any) -> Any:
        """`x` if it lies in the bounds (NaN never does)."""
        lo, hi = self.bounds()
        if not (lo < x if self.low_open else lo <= x) or not x <= hi:
            raise self.fail(raw)
        return x

    def integer(self, raw: Any) -> int:
        if isinstance(raw, bool) and not self.BOOL_IS_NUMBER:
            raise ValueError(raw)
        if isinstance(raw, float) and not raw.is_integer():
            raise ValueError(raw)
        return int(raw.strip()) if isinstance(raw, str) else int(raw)

    def real(self, raw: Any) -> float:
        if isinstance(raw, bool) and not self.BOOL_IS_NUMBER:
            raise ValueError(raw)
        return float(raw.strip()) if isinstance(raw, str) else float(raw)

    def boolean(self, raw: Any) -> bool:
        if isinstance(raw, bool):
            return raw
        text = str(raw).strip().lower()
        if not isinstance(raw, float):
            if text in self.TRUE:
                return True
            if text in self.FALSE:
                return False
        raise self.fail(raw)

    def triple(self, raw: Any) -> tuple[float, float, float]:
        """Three reals in the bounds from text, a sequence of three, or one grey number."""
        if isinstance(raw, str):
            parts = self.colour_text(raw)
        elif self.is_sequence(raw):
            parts = [raw[i] for i in range(len(raw))]
        else:
            parts = [raw]
        if len(parts) == 1:
            parts = parts * 3
        if len(parts) != 3:
            raise self.fail(raw)
        return tuple(self.check(self.real(p), raw) for p in parts)


__all__ = ["Declaration", "COMMON_KINDS"]
