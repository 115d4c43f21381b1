"""halftone: dots of brightness-dependent radius on a 3D or screen grid (S5.6; Hall 1999).

g = dark where `halftone_mask` holds (|p - round(p / d) d| < r), light elsewhere; lifting after
West, Mukherjee, Yue (2026). Formulas and rationale: docs/design/screen_space_patterns.md.
- spacing_px (float, default 8, > 0): grid interval on screen, in pixels
- spacing (float, default auto, > 0): grid interval d in scene units; given, it replaces spacing_px
- max_radius_fraction (float, default 0.75, in (0, 1]): darkest dot's radius / half the diagonal
- tones (floats, default auto): the tone curve, as in `hatching`; r = (1 - F(u)) r_max
- u_min (float), u_max (float, > u_min): a linear ramp instead of the tone curve
- dark (colour, default 0.1,0.1,0.15), light (colour, default 0.97,0.95,0.9)
- lift (choice, default canonical): canonical (image coordinate s) or position (own projection)
"""
from __future__ import annotations

import math

from styletrace.gate import dr, mi
from styletrace.styles.base import Param, Projection, Style, Vertex, brightness, projection
from styletrace.styles.hatching import BrightnessRange, coverage, tone_params
from styletrace.styles.registry import register_style
from styletrace.styles.tone import tone_inverse


def dot_radius(u: mi.Float, r_max: float, u_min: float = 0.05, u_max: float = 0.9) -> mi.Float:
    """r = (1 - clamp((u - u_min) / (u_max - u_min), 0, 1)) r_max, the linear ramp's radius.

    Args:
        u: brightness per lane (mi.Float); r_max: the largest radius.
        u_min, u_max: the ramp's ends (largest dot, no dot).

    Returns:
        mi.Float in [0, r_max].
    """
    return coverage(u, u_min, u_max) * r_max


def halftone_mask(p: mi.Point3f, u: mi.Float, spacing: float, r_max: float,
                  u_min: float = 0.05, u_max: float = 0.9) -> mi.Bool:
    """True where p is closer than r(u) to its nearest point of the 3D grid (the linear ramp).

    Args:
        p: world points (mi.Point3f); u: their brightness (mi.Float).
        spacing: the grid interval d (scene units); r_max: the largest radius.
        u_min, u_max: the ramp's ends.

    Returns:
        mi.Bool.
    """
    g = dr.round(mi.Vector3f(p) * (1.0 / spacing)) * spacing
    r = dot_radius(u, r_max, u_min, u_max)
    return dr.squared_norm(mi.Vector3f(p) - g) < r * r


def grid_distance(p: mi.Point3f, spacing: float) -> mi.Float:
    """Distance from p to its nearest point of the 3D grid.

    Args:
        p: world points (mi.Point3f); spacing: the grid interval d (scene units).

    Returns:
        mi.Float, in scene units.
    """
    g = dr.round(mi.Vector3f(p) * (1.0 / spacing)) * spacing
    return dr.norm(mi.Vector3f(p) - g)


def screen_distance(p: mi.Point3f, proj: Projection, spacing_px: float,
                    s: mi.Point2f | None = None) -> mi.Float:
    """Distance in pixels from p's screen position (the image coordinate `s` where given) to its
    nearest screen grid point.

    Args:
        p: world points (mi.Point3f); proj: the sensor's Projection (used where s is None).
        spacing_px: the grid interval, in pixels.
        s: the image coordinates (mi.Point2f, pixels), or None: p's own projection.

    Returns:
        mi.Float, in pixels.
    """
    x, y = proj.pixels(p) if s is None else (s.x, s.y)
    gx = dr.round(x * (1.0 / spacing_px)) * spacing_px
    gy = dr.round(y * (1.0 / spacing_px)) * spacing_px
    return dr.sqrt(dr.square(x - gx) + dr.square(y - gy))


def screen_halftone_mask(
    p: mi.Point3f,
    u: mi.Float,
    proj: Projection,
    spacing_px: float,
    r_max_px: float,
    ramp: tuple[float, float] = (0.05, 0.9),
    s: mi.Point2f | None = None,
) -> mi.Bool:
    """True where p's screen position (the image coordinate `s` where given) is closer than r(u)
    pixels to its nearest screen grid point (the linear ramp).

    Args:
        p: world points (mi.Point3f); u: their brightness (mi.Float).
        proj: the sensor's Projection; spacing_px: the grid interval, in pixels.
        r_max_px: the largest radius, in pixels; ramp: the ramp's ends (u_min, u_max), as
            `BrightnessRange.u_range` gives them.
        s: the image coordinates (mi.Point2f), or None: p's own projection.

    Returns:
        mi.Bool.
    """
    x, y = proj.pixels(p) if s is None else (s.x, s.y)
    gx = dr.round(x * (1.0 / spacing_px)) * spacing_px
    gy = dr.round(y * (1.0 / spacing_px)) * spacing_px
    r = dot_radius(u, r_max_px, *ramp)
    return dr.square(x - gx) + dr.square(y - gy) < r * r


@register_style
class Halftone(BrightnessRange, Style):
    """The halftone style (the module doc).

    Args:
        **values: its parameters (the module doc), as `Style` takes them.

    Raises:
        StyleError: a bad value, or a bad tone range.
    """

    name = "halftone"
    summary = ("half-tone: dark dots on a screen grid (or a 3D grid), radius growing as brightness "
               "falls")
    params = (
        Param(
            "spacing_px",
            "float",
            8.0,
            "grid interval on screen (pixels, a square grid of the image); used "
            "unless spacing is given",
            low=0.0,
            low_open=True,
        ),
        Param(
            "spacing",
            "float",
            None,
            "grid interval d of a 3D grid (scene units), replacing spacing_px",
            low=0.0,
            low_open=True,
            auto="not used: a screen grid spacing_px apart",
        ),
        Param(
            "max_radius_fraction",
            "float",
            0.75,
            "largest radius as a fraction of half the cell diagonal "
            "(sqrt(3) d / 2 in 3D, sqrt(2) spacing_px / 2 on screen)",
            low=0.0,
            high=1.0,
            low_open=True,
        ),
        *tone_params("dots are largest", "dots vanish"),
        Param("dark", "color", (0.1, 0.1, 0.15), "colour inside the dots", low=0.0),
        Param("light", "color", (0.97, 0.95, 0.9), "colour outside the dots", low=0.0),
        Param(
            "lift",
            "choice",
            "canonical",
            "where the screen grid is evaluated: the vertex's image coordinate "
            "(canonical: LLaT's mirror-anchor map) or its own position's projection (position)",
            choices=("canonical", "position"),
        ),
    )
    default_inner = 16

    def __init__(self, **values):
        super().__init__(**values)
        self.projection = Projection()

    def validate(self) -> None:
        self.check_u_range()

    @property
    def r_max(self) -> float:
        """Largest dot radius: scene units on the 3D grid (spacing given), pixels on the screen
        grid."""
        if self.spacing is None:
            return self.max_radius_fraction * 0.5 * math.sqrt(2.0) * self.spacing_px
        return self.max_radius_fraction * 0.5 * math.sqrt(3.0) * self.spacing

    def prepare(self, scene: mi.Scene) -> None:
        self.projection = projection(scene)

    @property
    def wants_coordinate(self) -> bool:
        """The integrator computes Vertex.s for this style (canonical lifting of the screen
        grid)."""
        return self.spacing is None and self.lift == "canonical"

    def _coordinate(self, v: Vertex):
        return v.s if self.wants_coordinate else None

    def _distance(self, v: Vertex) -> mi.Float:
        """v's distance to its nearest grid point: pixels on the screen grid, scene units on the 3D
        grid."""
        if self.spacing is None:
            return screen_distance(v.p, self.projection, self.spacing_px, self._coordinate(v))
        return grid_distance(v.p, self.spacing)

    def apply(self, I: mi.Color3f, v: Vertex) -> mi.Color3f:
        dot = self._distance(v) < self.toned(brightness(I)) * self.r_max
        return dr.select(dot, mi.Color3f(*self.dark), mi.Color3f(*self.light))

    def step_thresholds(self, v: Vertex) -> tuple:
        """The brightness at which the dot's edge passes v, where r(u) = d; none (+inf) where v is
        farther than r_max from its grid point (never inside a dot)."""
        d = self._distance(v)
        if self.uses_tones:
            t = tone_inverse(1.0 - d * (1.0 / self.r_max), self.tones)
        else:
            u_min, u_max = self.u_range()
            t = u_max - d * ((u_max - u_min) / self.r_max)
        return (dr.select(d < self.r_max, t, mi.Float(dr.inf)),)

    def curvature(self, I: mi.Color3f, v: Vertex, h: mi.Float) -> mi.Color3f:
        return mi.Color3f(0.0)  # two colours: all of g's change is at the threshold
