"""One declaration per setting, for the integrator's properties and the styles' parameters alike.

    Declaration(name, kind, default, doc, low=..., high=..., low_open=..., choices=...)

A `Declaration` holds a setting's kind, default, bounds, choices and doc line, and parses the
common kinds (`parse`): int (exact), float (in bounds, never NaN), bool, a choice, an RGB triple.
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
    """One setting (see the module doc); a frozen dataclass.

    Args:
        name, kind, default, doc: the setting's name, kind (a key of COMMON_KINDS or the
            subclass's own), default value and one-line doc.
        low, high: bounds of a number (or of each component of a colour); None: unbounded.
        low_open: the low end is excluded.
        choices: the strings a choice accepts (empty: any string).
    """

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
    # True/False may stand for 1/0 in an int or float
    BOOL_IS_NUMBER: ClassVar[bool] = False
    STRIP_CHOICE: ClassVar[bool] = False                      # ' soft ' is the choice 'soft'
    # the common kind that a kind not named parses as
    OTHER_KIND: ClassVar[str | None] = None

    # What a side supplies:
    def fail(self, raw: Any) -> StyletraceError:
        """The one-line error for a bad value; each subclass supplies it.

        Args:
            raw: the value refused.

        Returns:
            The error to raise (SettingsError, StyleError in the subclasses).

        Raises:
            NotImplementedError: always, here in the base class.
        """
        raise NotImplementedError

    def bounds(self) -> tuple[float, float]:
        """The closed range of admissible values (of each component of a colour)."""
        return (-math.inf if self.low is None else self.low,
                math.inf if self.high is None else self.high)

    def colour_text(self, text: str) -> list[Any]:
        """The components of a colour written as text.

        Args:
            text: the colour as written: 'r,g,b' or one grey value (subclasses accept more).

        Returns:
            Its components, not yet converted (the text split at commas).
        """
        return text.split(",")

    def is_sequence(self, raw: Any) -> bool:
        """Whether `raw` holds several values rather than one.

        Args:
            raw: a value as given by a front end.

        Returns:
            True for a list or tuple.
        """
        return isinstance(raw, (list, tuple))

    # The one parsing of the common kinds:
    def parse(self, raw: Any) -> Any:
        """The value `raw` as this setting declares it.

        Args:
            raw: a CLI string, a Mitsuba property or a Python value.

        Returns:
            The converted value, checked against the bounds and choices.

        Raises:
            StyletraceError: `fail(raw)` (the subclass's error) for a value of the wrong kind, out
                of bounds or not among the choices.
        """
        try:
            return self.convert(raw)
        except StyletraceError:
            raise
        except (TypeError, ValueError, IndexError, OverflowError) as exc:
            raise self.fail(raw) from exc

    def convert(self, raw: Any) -> Any:
        """Convert `raw` to a common kind; a subclass handles its own kinds and hands the rest here.

        Args:
            raw: the value as given.

        Returns:
            An int, a float, a bool, a choice's string or an (r, g, b) tuple.

        Raises:
            StyletraceError: `fail(raw)` for a value out of bounds or not among the choices.
            TypeError, ValueError, IndexError, OverflowError: a value that does not convert.
            AssertionError: a kind that neither COMMON_KINDS nor OTHER_KIND names.
        """
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
        """Check a converted value against the bounds (`low_open`: low excluded).

        Args:
            x: the converted number.
            raw: the value as given, for the error.

        Returns:
            `x` unchanged.

        Raises:
            StyletraceError: `fail(raw)` where `x` lies outside the bounds (NaN always does).
        """
        lo, hi = self.bounds()
        if not (lo < x if self.low_open else lo <= x) or not x <= hi:
            raise self.fail(raw)
        return x

    def integer(self, raw: Any) -> int:
        """`raw` as an exact int, unchecked.

        Args:
            raw: an int, a float without fraction or an int's text (stripped); a bool only where
                BOOL_IS_NUMBER.

        Returns:
            The int.

        Raises:
            ValueError, TypeError: a value that is no exact int.
        """
        if isinstance(raw, bool) and not self.BOOL_IS_NUMBER:
            raise ValueError(raw)
        if isinstance(raw, float) and not raw.is_integer():
            raise ValueError(raw)
        return int(raw.strip()) if isinstance(raw, str) else int(raw)

    def real(self, raw: Any) -> float:
        """`raw` as a float, unchecked (inf and NaN pass; `check` tests the bounds).

        Args:
            raw: a number or a number's text (stripped); a bool only where BOOL_IS_NUMBER.

        Returns:
            The float.

        Raises:
            ValueError, TypeError, OverflowError: a value that is no number.
        """
        if isinstance(raw, bool) and not self.BOOL_IS_NUMBER:
            raise ValueError(raw)
        return float(raw.strip()) if isinstance(raw, str) else float(raw)

    def boolean(self, raw: Any) -> bool:
        """`raw` as a bool.

        Args:
            raw: a bool, or a word of TRUE or FALSE (any case, stripped); a float never counts.

        Returns:
            The bool.

        Raises:
            StyletraceError: `fail(raw)` for anything else.
        """
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
        """Three reals in the bounds from text, a sequence of three, or one grey number.

        Args:
            raw: text (`colour_text`), a sequence (`is_sequence`) of one or three values, or one
                number; one value is grey (repeated three times).

        Returns:
            (r, g, b) as floats, each in the bounds.

        Raises:
            StyletraceError: `fail(raw)` for other than 1 or 3 components, or one out of bounds.
            ValueError, TypeError: a component that is no number (`parse` makes it `fail(raw)`).
        """
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
