"""Piecewise-linear colour gradients over brightness, evaluated inside kernels.

A gradient is a list of stops (position u_i, colour c_i), positions strictly increasing.
`eval(u)` clamps u to [u_0, u_last] (the colour-map style of S5.1); `eval(u, extrapolate=True)`
continues the end segments linearly, which keeps the map affine in u for a two-stop gradient
(the sepia style of S5.4, whose gradient must cover [0, inf)).
"""
from __future__ import annotations

import math
from typing import Any

import numpy as np

from styletrace.errors import StyleError
from styletrace.gate import dr, mi

PRESETS = {
    # dark blue -> terracotta -> warm sand: reads well on the built-in scenes' brightness range
    "dusk": "0:#161a3a;0.25:#4b3f72;0.5:#e07a5f;0.9:#f2cc8f;1.2:#fffbe6",
    "grey": "0:#000000;1:#ffffff",
    "heat": "0:#000000;0.3:#7a0403;0.6:#f26b0f;0.9:#fde725;1.2:#ffffff",
    "cool": "0:#0b1d51;0.5:#3a7ca5;1:#d9f0ff",
    "sepia": "0:#000000;1:#c4a27a",
}


class Gradient:
    """Colour stops over brightness; `spec` is the text it was parsed from.

    Args:
        stops: [(position u_i, (r, g, b)), ...], at least two, positions finite and strictly
            increasing (in float32 too).
        spec: the text the stops were parsed from (what `Param.show` prints).

    Raises:
        ValueError: fewer than two stops, or positions that do not strictly increase.
    """

    def __init__(self, stops: list[tuple[float, tuple[float, float, float]]], spec: str):
        if len(stops) < 2:
            raise ValueError(f"gradient {spec!r} needs at least two stops")
        pos = [p for p, _ in stops]
        # eval divides by the gaps in float32: they must be positive there too (not flushed to 0)
        gaps = np.diff(np.asarray(pos, dtype=np.float32))
        if not all(math.isfinite(p) for p in pos) or not np.all(gaps >= np.finfo(np.float32).tiny):
            raise ValueError(f"gradient {spec!r}: stop positions must be finite and strictly "
                             "increase")
        self.stops = stops
        self.spec = spec

    @staticmethod
    def presets() -> list[str]:
        return sorted(PRESETS)

    @staticmethod
    def parse_color(text: str) -> list[float]:
        """A colour from text.

        Args:
            text: '#rrggbb', '#rgb', 'r,g,b', 'r g b', or one grey number.

        Returns:
            [r, g, b] floats (hex digits scaled to [0, 1]).

        Raises:
            ValueError: anything else.
        """
        s = text.strip()
        if s.startswith("#"):
            h = s[1:]
            if len(h) == 3:
                h = "".join(c * 2 for c in h)
            if len(h) != 6:
                raise ValueError(f"bad hex colour {text!r}")
            return [int(h[i:i + 2], 16) / 255.0 for i in (0, 2, 4)]
        vals = [float(t) for t in s.replace(",", " ").split()]
        if len(vals) == 1:
            vals *= 3
        if len(vals) != 3:
            raise ValueError(f"bad colour {text!r}")
        return vals

    @classmethod
    def parse(cls, raw: Any) -> "Gradient":
        """From a preset name, a 'pos:colour;...' string, or a sequence of (pos, colour) pairs.

        Args:
            raw: a name in PRESETS, 'pos:colour;pos:colour;...' (colours as `parse_color`
                reads them), or a sequence of (pos, (r, g, b)) pairs.

        Returns:
            The Gradient.

        Raises:
            StyleError: a bad gradient (one line naming what is expected and the presets).
        """
        allowed = (
            "expected 'pos:colour;pos:colour;...' with finite positions that strictly increase (in "
            "float32 too) and colours '#rrggbb' or 'r,g,b', or a "
            "preset: " + ", ".join(cls.presets())
        )
        try:
            if isinstance(raw, str):
                spec = raw.strip()
                text = PRESETS.get(spec, spec)
                stops = []
                for part in text.split(";"):
                    if not part.strip():
                        continue
                    pos, col = part.split(":", 1)
                    stops.append((float(pos), tuple(cls.parse_color(col))))
            else:
                spec = ";".join(f"{float(p):g}:{','.join(f'{float(c):g}' for c in col)}"
                                for p, col in raw)
                stops = [(float(p), tuple(float(c) for c in col)) for p, col in raw]
            return cls(stops, spec)
        except (ValueError, TypeError) as exc:
            raise StyleError(f"bad gradient {raw!r}: {allowed}") from exc

    def eval(self, u, extrapolate: bool = False) -> mi.Color3f:
        """Colour at brightness u, piecewise linear between the stops.

        Args:
            u: brightness per lane (mi.Float).
            extrapolate: continue the end segments linearly instead of clamping to the end stops.

        Returns:
            mi.Color3f.
        """
        (p0, c0) = self.stops[0]
        out = mi.Color3f(*c0)
        last = len(self.stops) - 2
        for i, ((pa, ca), (pb, cb)) in enumerate(zip(self.stops, self.stops[1:])):
            t = (u - pa) / (pb - pa)
            lo = -dr.inf if (extrapolate and i == 0) else 0.0
            hi = dr.inf if (extrapolate and i == last) else 1.0
            t = dr.clip(t, lo, hi)
            out += (mi.Color3f(*cb) - mi.Color3f(*ca)) * t
        return out
