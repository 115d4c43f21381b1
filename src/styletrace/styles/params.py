"""Typed, validated style parameters.

A style declares its parameters once; the CLI (`--set key=value` strings), Mitsuba properties
(XML or dict values) and the docs all go through `Param.parse`, so every front end accepts the
same spellings and rejects bad values with the same one-line message.

Every real value (a number, a list entry, a colour or vector component) is finite and lies in
[-LIMIT, LIMIT] unless the parameter's own range is narrower. The kernels compute in float32
(largest value 3.4e38): a product of two parameters and a radiance up to 1e20 then stays finite, and
no value turns into inf when it is converted to float32. Parameters whose formula overflows sooner
carry their own bounds, derived where they are declared.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, ClassVar, Sequence

from styletrace.declaration import COMMON_KINDS, Declaration
from styletrace.errors import StyleError
from styletrace.styles.gradient import Gradient

#: Default bound on the magnitude of every real parameter value (see the module's reference block).
LIMIT = 1e6


def _is_seq(value: Any) -> bool:
    return isinstance(value, (list, tuple)) or (
        hasattr(value, "__len__") and hasattr(value, "__getitem__") and not isinstance(value, str)
    )


def _floats(text: str) -> list[float]:
    return [float(t) for t in text.replace(",", " ").split()]


@dataclass(frozen=True, init=False)
class Param(Declaration):
    """One style parameter: the styles' side of the shared `styletrace.declaration.Declaration`,
    which parses the common kinds (float, int, bool, color, choice); here the `auto` rule, the
    vector, floats and gradient kinds, the ±LIMIT bound on reals and the styles' spellings (bool
    also yes/no/on/off, True/False as numbers, a colour also '#rrggbb' or 'r g b', a choice
    stripped).

    Args:
        name, default, doc: the parameter's name, default (None: auto) and docs' line.
        kind: float | int | bool | color | vector | floats | gradient | choice.
        low, high: bound a real or each component (None: ±LIMIT for reals, none for ints).
        low_open: the low end excluded; choices: the strings a choice accepts.
        auto: for a default of None, the rule that derives the value (from the scene or others).

    Takes more than 7 parameters: it is a declaration, and each argument is one of its declared
    attributes (`auto` and `Declaration`'s fields).
    """

    #: for a default of None ('auto'): the rule that derives the value (from the scene or other
    #: parameters)
    auto: str = ""

    TRUE: ClassVar[tuple[str, ...]] = ("1", "true", "yes", "on")
    FALSE: ClassVar[tuple[str, ...]] = ("0", "false", "no", "off")
    BOOL_IS_NUMBER: ClassVar[bool] = True
    STRIP_CHOICE: ClassVar[bool] = True

    def __init__(
        self,
        name: str,
        kind: str,
        default: Any,
        doc: str,
        low: float | None = None,
        high: float | None = None,
        low_open: bool = False,
        choices: Sequence[str] = (),
        auto: str = "",
    ):
        Declaration.__init__(self, name, kind, default, doc, low, high, low_open, tuple(choices))
        object.__setattr__(self, "auto", auto)

    def allowed(self) -> str:
        """Human description of the admissible values, used in errors and in `styletrace styles`."""
        if self.default is None:
            return self._allowed() + ", or auto"
        return self._allowed()

    def _allowed(self) -> str:
        if self.kind == "choice":
            return "one of " + ", ".join(self.choices)
        if self.kind == "gradient":
            return (
                "a gradient 'pos:colour;pos:colour;...' (colour '#rrggbb' or 'r,g,b') or a preset: "
                + ", ".join(Gradient.presets())
            )
        if self.kind == "color":
            return f"an RGB colour: 'r,g,b' with each value{self._range()}, or '#rrggbb'"
        if self.kind == "vector":
            return f"a non-zero 3D vector 'x,y,z' with each component{self._range()}"
        noun = {"float": "a number", "int": "an integer", "bool": "true or false",
                "floats": "a comma-separated list of numbers"}[self.kind]
        return noun + (self._range() if self.kind != "bool" else "")

    def bounds(self) -> tuple[float, float]:
        """The closed range of admissible values; reals default to [-LIMIT, LIMIT]."""
        if self.kind == "int":
            return super().bounds()
        return (-LIMIT if self.low is None else self.low, LIMIT if self.high is None else self.high)

    def _range(self) -> str:
        lo, hi = self.bounds()
        if self.kind == "int" and self.low is None and self.high is None:
            return ""
        lo_text = "-inf" if lo == -math.inf else f"{lo:g}"
        hi_text = "inf" if hi == math.inf else f"{hi:g}"
        return (f" in {'(' if self.low_open else '['}{lo_text}, "
                f"{hi_text}{')' if hi == math.inf else ']'}")

    def fail(self, value: Any) -> StyleError:
        """The error for a bad value of this parameter.

        Args:
            value: the value refused.

        Returns:
            A StyleError naming the value and what is allowed (to raise).
        """
        return StyleError(f"bad value {value!r} for parameter '{self.name}': expected "
                          f"{self.allowed()}")

    def colour_text(self, text: str) -> list[Any]:
        """The components of a colour written as text ('#rrggbb', or numbers).

        Args:
            text: the colour as written.

        Returns:
            Its components.
        """
        s = text.strip()
        return Gradient.parse_color(s) if s.startswith("#") else _floats(s)

    def is_sequence(self, raw: Any) -> bool:
        """Whether `raw` is a sequence of values rather than one value.

        Args:
            raw: a value as given by a front end.

        Returns:
            True where `raw` holds several values rather than one.
        """
        return _is_seq(raw)

    def parse(self, raw: Any) -> Any:
        """Turn a string, number, sequence or Mitsuba colour into the validated Python value.

        Args:
            raw: the value as given; 'auto' for a parameter whose default is derived.

        Returns:
            The validated value (None for 'auto').

        Raises:
            StyleError: a value of the wrong kind or outside the parameter's bounds.
        """
        if self.default is None and isinstance(raw, str) and raw.strip().lower() == "auto":
            return None
        return super().parse(raw)

    def convert(self, raw: Any) -> Any:
        """Convert a value other than 'auto' to this parameter's kind and check its bounds.

        Args:
            raw: the value as given.

        Returns:
            The validated value.

        Raises:
            StyleError: a value of the wrong kind or outside the parameter's bounds.
        """
        k = self.kind
        if k == "vector":
            vals = self.triple(raw)
            if sum(v * v for v in vals) == 0:
                raise self.fail(raw)
            return vals
        if k == "floats":
            vals = (_floats(raw) if isinstance(raw, str)
                    else ([float(v) for v in raw] if _is_seq(raw) else [float(raw)]))
            if not vals:
                raise self.fail(raw)
            return tuple(self.check(v, raw) for v in vals)
        if k == "gradient":
            gradient = raw if isinstance(raw, Gradient) else Gradient.parse(raw)
            for pos, colour in gradient.stops:
                for v in (pos, *colour):
                    if not -LIMIT <= v <= LIMIT:
                        raise StyleError(
                            f"bad gradient {gradient.spec!r} for parameter '{self.name}': stop "
                            f"positions and colour values must be finite numbers in "
                            f"[{-LIMIT:g}, {LIMIT:g}]"
                        )
            return gradient
        if k in COMMON_KINDS:
            return super().convert(raw)
        raise AssertionError(f"unknown parameter kind {k}")

    def explain(self) -> str:
        """The doc line with the rule of an 'auto' default, as `styletrace styles` and the docs show
        it."""
        return f"{self.doc}; auto: {self.auto}" if self.auto else self.doc

    def show(self, value: Any) -> str:
        """Format a value the way `parse` reads it back.

        Args:
            value: a validated value, or None for a default the style derives itself.

        Returns:
            The text ('auto' for None).
        """
        if value is None:
            return "auto"
        if isinstance(value, Gradient):
            return value.spec
        if isinstance(value, tuple):
            return ",".join(f"{v:g}" for v in value)
        if isinstance(value, bool):
            return "true" if value else "false"
        if isinstance(value, float):
            return f"{value:g}"
        return str(value)
