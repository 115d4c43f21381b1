"""Blender's Mist pass: how far each camera sample's first hit lies inside the World's mist, 0 on
the camera's side of `start` and 1 beyond `start + depth`, shaped by the falloff.

    mist = parse_mist("5,25,quadratic")    # Mist(start=5.0, depth=25.0, falloff='quadratic')
    m = mist.amount(distance)              # per lane, mi.Float in [0, 1]

The distance is the camera position's to the hit (an orthographic camera's: along its view axis),
t = clamp((distance - start) / depth, 0, 1), then t^2 (quadratic), t (linear) or sqrt(t) (inverse
quadratic): the values Cycles 5.0 writes (measured, tests/blender/test_more_passes.py). Docs:
docs/passes.md.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from styletrace.errors import UsageError
from styletrace.gate import dr, mi

#: Blender's falloffs (`world.mist_settings.falloff`, lower case) and the power of t each takes
FALLOFFS = {"quadratic": 2.0, "linear": 1.0, "inverse_quadratic": 0.5}


@dataclass(frozen=True)
class Mist:
    """The World's mist settings; the defaults are a new Blender World's.

    Args:
        start: distance from the camera where the mist begins, in scene units (>= 0).
        depth: the distance over which it rises from 0 to 1 (> 0).
        falloff: one of `FALLOFFS`.
    """
    start: float = 5.0
    depth: float = 25.0
    falloff: str = "quadratic"

    def amount(self, distance):
        """The mist at these distances from the camera.

        Args:
            distance: mi.Float.

        Returns:
            mi.Float in [0, 1].
        """
        # opaque: a new setting reuses the compiled kernel
        start = dr.opaque(mi.Float, float(self.start))
        scale = dr.opaque(mi.Float, 1.0 / float(self.depth))
        t = dr.clip((distance - start) * scale, 0.0, 1.0)
        power = FALLOFFS[self.falloff]
        return t * t if power == 2.0 else dr.sqrt(t) if power == 0.5 else t


def parse_mist(value: Any, name: str = "mist") -> Mist:
    """The mist settings given.

    Args:
        value: None (Blender's defaults), a Mist, 'START,DEPTH,FALLOFF' or (start, depth,
            falloff).
        name: how the caller names the setting, for the error ('--mist', 'mist').

    Returns:
        The Mist.

    Raises:
        UsageError: a start below 0, a depth not above 0, a falloff not in `FALLOFFS`, or not
            three items (one line naming the bad value and the allowed ones).
    """
    if value is None:
        return Mist()
    if isinstance(value, Mist):
        items = (value.start, value.depth, value.falloff)
    else:
        items = value.split(",") if isinstance(value, str) else list(value)
    expected = f"expected START,DEPTH,FALLOFF with START >= 0, DEPTH > 0, FALLOFF one of " \
               f"{', '.join(FALLOFFS)}"
    if len(items) != 3:
        raise UsageError(f"bad value {value!r} for {name}: {expected}")
    try:
        start, depth = float(items[0]), float(items[1])
    except (TypeError, ValueError):
        raise UsageError(f"bad value {value!r} for {name}: {expected}") from None
    falloff = str(items[2]).strip().lower()
    if not start >= 0 or not depth > 0 or falloff not in FALLOFFS:
        raise UsageError(f"bad value {value!r} for {name}: {expected}")
    return Mist(start, depth, falloff)


__all__ = ["FALLOFFS", "Mist", "parse_mist"]
