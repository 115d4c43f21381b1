"""Typed, validated style parameters.

A style declares its parameters once; the CLI (`--set key=value` strings), Mitsuba properties
(XML or dict values) and the docs all go through `Param.parse`, so every front end accepts the
same spellings and rejects bad values with the same one-line message.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Sequence

from ..errors import StyleError
from .gradient import Gradient


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

    def allowed(self) -> str:
        """Human description of the admissible values, used in errors and in `styletrace styles`."""
        if self.kind == "choice":
            return "one of " + ", ".join(self.choices)
        if self.kind == "color":
            return "an RGB colour: 'r,g,b' floats or '#rrggbb'"
        if self.kind == "vector":
            return "a 3D vector 'x,y,z'"
        if self.kind == "gradient":
            return "a gradient 'pos:colour;pos:colour;...' (colour '#rrggbb' or 'r,g,b') or a preset: " + \
                ", ".join(Gradient.presets())
        rng = ""
        if self.low is not None or self.high is not None:
            lo = "-inf" if self.low is None else f"{self.low:g}"
            hi = "inf" if self.high is None else f"{self.high:g}"
            rng = f" in {'(' if self.low_open else '['}{lo}, {hi}]"
        noun = {"float": "a number", "int": "an integer", "bool": "true or false",
                "floats": "a comma-separated list of numbers"}[self.kind]
        return noun + rng

    def fail(self, value: Any) -> StyleError:
        return StyleError(f"bad value {value!r} for parameter '{self.name}': expected {self.allowed()}")

    def _check_range(self, x: float, raw: Any) -> None:
        if x != x:  # NaN
            raise self.fail(raw)
        if self.low is not None and (x < self.low or (self.low_open and x == self.low)):
            raise self.fail(raw)
        if self.high is not None and x > self.high:
            raise self.fail(raw)

    def parse(self, raw: Any) -> Any:
        """Turn a string, number, sequence or Mitsuba colour into the validated Python value."""
        try:
            value = self._convert(raw)
        except StyleError:
            raise
        except (TypeError, ValueError, IndexError) as exc:
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
            if isinstance(raw, Gradient):
                return raw
            return Gradient.parse(raw)
        if k == "choice":
            s = str(raw).strip()
            if s not in self.choices:
                raise self.fail(raw)
            return s
        raise AssertionError(f"unknown parameter kind {k}")

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
