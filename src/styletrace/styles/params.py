"""Typed, validated style parameters.

A style declares its parameters once; the CLI (`--set key=value` strings), Mitsuba properties
(XML or dict values) and the docs all go through `Param.parse`, so every front end accepts the
same spellings and rejects bad values with the same one-line message.

Every real value (a number, a list entry, a colour or vector component) is finite and lies in
[-LIMIT, LIMIT] unless the parameter's own range is narrower. The kernels compute in float32 (largest
value 3.4e38): a product of two parameters and a radiance up to 1e20 then stays finite, and no value
turns into inf when it is converted to float32. Parameters whose formula overflows sooner carry their
own bounds, derived where they are declared.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any, Sequence

from ..errors import StyleError
from .gradient import Gradient


#: Default bound on the magnitude of every real parameter value (see the module's reference block).
LIMIT = 1e6


def _is_seq(value: Any) -> bool:
    return isinstance(value, (list, tuple)) or (hasattr(value, "__len__") and hasattr(value, "__getitem__")
                                                and not isinstance(value, str))


def _floats(text: str) -> list[float]:
    return [float(t) for t in text.replace(",", " ").split()]


@dataclass(frozen=True)
class Param:
    """One parameter: `kind` is float | int | bool | color | vector | floats | gradient | choice."""

    name: str
    kind: str
    default: Any
    doc: str
    low: float | None = None
    high: float | None = None
    low_open: bool = False  # True: the bound itself is not allowed (e.g. gamma > 0)
    choices: Sequence[str] = field(default_factory=tuple)
    #: for a default of None ('auto'): the rule that derives the value (from the scene or other parameters)
    auto: str = ""

    def allowed(self) -> str:
        """Human description of the admissible values, used in errors and in `styletrace styles`."""
        if self.default is None:
            return self._allowed() + ", or auto"
        return self._allowed()

    def _allowed(self) -> str:
        if self.kind == "choice":
            return "one of " + ", ".join(self.choices)
        if self.kind == "gradient":
            return "a gradient 'pos:colour;pos:colour;...' (colour '#rrggbb' or 'r,g,b') or a preset: " + \
                ", ".join(Gradient.presets())
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
            return (-math.inf if self.low is None else self.low, math.inf if self.high is None else self.high)
        return (-LIMIT if self.low is None else self.low, LIMIT if self.high is None else self.high)

    def _range(self) -> str:
        lo, hi = self.bounds()
        if self.kind == "int" and self.low is None and self.high is None:
            return ""
        lo_text = "-inf" if lo == -math.inf else f"{lo:g}"
        hi_text = "inf" if hi == math.inf else f"{hi:g}"
        return f" in {'(' if self.low_open else '['}{lo_text}, {hi_text}{')' if hi == math.inf else ']'}"

    def fail(self, value: Any) -> StyleError:
        return StyleError(f"bad value {value!r} for parameter '{self.name}': expected {self.allowed()}")

    def _check_range(self, x: float, raw: Any) -> None:
        lo, hi = self.bounds()
        if not (lo <= x <= hi) or (self.low_open and x == lo):  # NaN fails every comparison
            raise self.fail(raw)

    def parse(self, raw: Any) -> Any:
        """Turn a string, number, sequence or Mitsuba colour into the validated Python value ('auto': None, for
        a parameter whose default is derived)."""
        if self.default is None and isinstance(raw, str) and raw.strip().lower() == "auto":
            return None
        try:
            value = self._convert(raw)
        except StyleError:
            raise
        except (TypeError, ValueError, IndexError, OverflowError) as exc:
            raise self.fail(raw) from exc
        return value

    def _convert(self, raw: Any) -> Any:
        k = self.kind
        if k == "float":
            x = float(raw)
            self._check_range(x, raw)
            return x
        if k == "int":
            if isinstance(raw, float) and not raw.is_integer():
                raise self.fail(raw)
            x = int(str(raw).strip()) if isinstance(raw, str) else int(raw)
            self._check_range(x, raw)
            return x
        if k == "bool":
            if isinstance(raw, bool):
                return raw
            s = str(raw).strip().lower()
            if s in ("1", "true", "yes", "on"):
                return True
            if s in ("0", "false", "no", "off"):
                return False
            raise self.fail(raw)
        if k in ("color", "vector"):
            if isinstance(raw, str):
                s = raw.strip()
                vals = Gradient.parse_color(s) if s.startswith("#") else _floats(s)
            else:
                vals = [float(raw[i]) for i in range(len(raw))] if _is_seq(raw) else [float(raw)] * 3
            if len(vals) == 1:
                vals = vals * 3
            if len(vals) != 3:
                raise self.fail(raw)
            for v in vals:
                self._check_range(v, raw)
            if k == "vector" and sum(v * v for v in vals) == 0:
                raise self.fail(raw)
            return tuple(vals)
        if k == "floats":
            vals = _floats(raw) if isinstance(raw, str) else ([float(v) for v in raw] if _is_seq(raw) else [float(raw)])
            if not vals:
                raise self.fail(raw)
            for v in vals:
                self._check_range(v, raw)
            return tuple(vals)
        if k == "gradient":
            gradient = raw if isinstance(raw, Gradient) else Gradient.parse(raw)
            for pos, colour in gradient.stops:
                for v in (pos, *colour):
                    if not -LIMIT <= v <= LIMIT:
                        raise StyleError(f"bad gradient {gradient.spec!r} for parameter '{self.name}': stop "
                                         f"positions and colour values must be finite numbers in "
                                         f"[{-LIMIT:g}, {LIMIT:g}]")
            return gradient
        if k == "choice":
            s = str(raw).strip()
            if s not in self.choices:
                raise self.fail(raw)
            return s
        raise AssertionError(f"unknown parameter kind {k}")

    def explain(self) -> str:
        """The doc line with the rule of an 'auto' default, as `styletrace styles` and the docs show it."""
        return f"{self.doc}; auto: {self.auto}" if self.auto else self.doc

    def show(self, value: Any) -> str:
        """Format a value the way `parse` reads it back ('auto' for a default the style derives itself)."""
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
