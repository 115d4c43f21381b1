"""The line dictionary of `line_mode lifted`: `line_types`, parsed into `LineType`s.

Reference: West, Mukherjee, Yue, "Lifting Lines and Tone" (2026), Section 4.3 (Eqs. 23, 31-34).

    line_types = "shape_id color=0.8,0,0; depth threshold=0.05 radius=1.5 count=16; normal"

Measurements: shape_id, material_id (any difference fires), depth (0.1 per pixel), normal (0.3).
Fields: threshold (> 0), stencil (disk | square), radius (pixels), count (1 .. 256), color. Empty:
one shape_id type. Types fire in priority order (docs/design/line_dictionary.md, docs/lines.md).
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from styletrace.config.declare import integer, number, rgb
from styletrace.errors import SettingsError

MEASUREMENTS = ("shape_id", "material_id", "depth", "normal")
STENCILS = ("disk", "square")
#: slope thresholds per pixel where the entry names none (ids fire on any difference: the value
#: is unused)
DEFAULT_THRESHOLD = {"shape_id": 0.5, "material_id": 0.5, "depth": 0.1, "normal": 0.3}
FIELDS = ("threshold", "stencil", "radius", "count", "color")


@dataclass(frozen=True)
class LineType:
    """One entry of a line dictionary (see the module doc); `priority`: lower fires first."""
    measurement: str = "depth"
    threshold: float = 1.0
    stencil: str = "disk"
    radius: float = 1.0
    count: int = 16
    color: tuple = (0.0, 0.0, 0.0)
    priority: int = 0


def parse_line_types(raw: Any, width: float, samples: int, color: tuple) -> tuple[LineType, ...]:
    """`line_types` (module doc) parsed, the line group's settings giving the fields' defaults.

    Args:
        raw: the `line_types` string, entries split by ';' (None or empty: one shape_id type).
        width: the line width in pixels; an entry's radius defaults to width / 2.
        samples: the default `count`; color: the default `color`, (r, g, b).

    Returns:
        One LineType per entry, in priority order (the first fires first).

    Raises:
        SettingsError: not a string, or a bad measurement, field, stencil or value (one line).
    """
    text = "" if raw is None else raw
    if not isinstance(text, str):
        raise SettingsError(f"bad value {raw!r} for 'line_types': expected a string like "
                            "'shape_id color=1,0,0; depth threshold=0.1'")
    entries = [e.strip() for e in text.split(";") if e.strip()] or ["shape_id"]
    out = []
    for priority, entry in enumerate(entries):
        words = entry.split()
        kind = words[0]
        if kind not in MEASUREMENTS:
            raise SettingsError(
                f"bad measurement {kind!r} in 'line_types' entry {entry!r}: expected one of "
                f"{', '.join(MEASUREMENTS)}"
            )
        fields: dict[str, Any] = {}
        for w in words[1:]:
            key, eq, val = w.partition("=")
            if not eq or key not in FIELDS:
                raise SettingsError(
                    f"bad field {w!r} in 'line_types' entry {entry!r}: expected key=value with "
                    f"key one of {', '.join(FIELDS)}"
                )
            if key in fields:
                raise SettingsError(f"field {key!r} given twice in 'line_types' entry {entry!r}")
            fields[key] = val
        stencil = fields.get("stencil", "disk")
        if stencil not in STENCILS:
            raise SettingsError(
                f"bad stencil {stencil!r} in 'line_types' entry {entry!r}: expected "
                f"{' or '.join(STENCILS)}"
            )
        where = f"line_types {kind}"
        out.append(
            LineType(
                measurement=kind,
                threshold=number(
                    f"{where} threshold",
                    fields.get("threshold", DEFAULT_THRESHOLD[kind]),
                    0.0,
                    low_open=True,
                ),
                stencil=stencil,
                radius=number(
                    f"{where} radius", fields.get("radius", width / 2.0), 0.0, 64.0, low_open=True
                ),
                count=integer(f"{where} count", fields.get("count", samples), 1, 256),
                color=rgb(f"{where} color", fields["color"]) if "color" in fields else tuple(color),
                priority=priority,
            )
        )
    return tuple(out)


def without_colours(raw: str) -> str:
    """`line_types` with every entry's own `color=` field dropped, the rest as given: each type then
    takes the line group's colour (the Blender add-on's line mask renders the lines once black and
    once white).

    Args:
        raw: a `line_types` string (not checked here).

    Returns:
        The entries without their `color=` words, joined by '; ' (empty entries dropped).
    """
    return "; ".join(" ".join(w for w in entry.split() if w.partition("=")[0] != "color")
                     for entry in raw.split(";") if entry.strip())


__all__ = ["LineType", "MEASUREMENTS", "STENCILS", "parse_line_types", "without_colours"]
