"""hatching: cross-hatching by slabs around planes through the view (S5.6; Deussen et al. 1999).

g = line_color where `hatch_mask` holds, else background (docs/design/screen_space_patterns.md).
- sets (int, default 3, in [1, 8]), angle (float, default 45): n directions, the first's (degrees)
- spacing_px (float, default 8, > 0), spacing (float, default auto, > 0): line distance on screen
  in pixels, or of world-space planes (given, it replaces spacing_px)
- thickness (float, default auto = 0.3 * the spacing, in (0, spacing)): line thickness d
- tones (floats, default auto), u_min (float), u_max (float, > u_min): the tone curve u_0 < ... <
  u_K (`tone.tone_knots`), or a linear ramp instead (unresolved: 0.05 and 0.9)
- line_color (colour, default 0.05,0.05,0.08), background (colour, default 0.97,0.95,0.9)
- lift (choice, default canonical), angle_reflected (float, default auto = angle): lines at the
  image coordinate s (LLaT, West et al. 2026) or own projection; first angle at path depth > 0
"""
from __future__ import annotations

import math
from typing import Sequence

from styletrace.gate import dr, mi
from styletrace.styles.base import (
    Param,
    Projection,
    Style,
    StyleError,
    Vertex,
    brightness,
    camera,
    camera_forward,
    increasing,
    projection,
)
from styletrace.styles.registry import register_style
from styletrace.styles.tone import tone_inverse, tone_knots, tone_of

Vec = tuple[float, float, float]


def camera_up(scene: mi.Scene) -> Vec:
    """World-space up vector of the scene's first sensor (its local +y); +y if there is none.

    Args:
        scene: a loaded mi.Scene.

    Returns:
        The unit up vector (x, y, z).
    """
    return camera(scene).up


def _cross(a: Sequence[float], b: Sequence[float]) -> Vec:
    return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])


def _unit(a: Sequence[float]) -> Vec:
    n = math.sqrt(sum(x * x for x in a))
    return tuple(x / n for x in a)


def plane_normals(view: Sequence[float], up: Sequence[float], sets: int,
                  angle_deg: float) -> list[Vec]:
    """Unit normals n_j perpendicular to `view`, at angles angle + j pi / sets around it.

    Args:
        view: the view direction; up: the camera's up (made perpendicular to view: e2).
        sets: the number of normals; angle_deg: the first one's angle from e1, in degrees.

    Returns:
        The normals, n_j = cos(theta_j) e1 + sin(theta_j) e2.
    """
    f = _unit(view)
    d = sum(a * b for a, b in zip(up, f))
    e2 = tuple(a - d * b for a, b in zip(up, f))
    # up parallel to view: any perpendicular will do
    if math.sqrt(sum(x * x for x in e2)) < 1e-6:
        helper = (1.0, 0.0, 0.0) if abs(f[0]) < 0.9 else (0.0, 1.0, 0.0)
        e2 = _cross(f, helper)
    e2 = _unit(e2)
    e1 = _unit(_cross(e2, f))
    out = []
    for j in range(sets):
        t = math.radians(angle_deg) + j * math.pi / sets
        c, s = math.cos(t), math.sin(t)
        out.append(tuple(c * a + s * b for a, b in zip(e1, e2)))
    return out


def coverage(u: mi.Float, u_min: float, u_max: float) -> mi.Float:
    """1 - clamp((u - u_min) / (u_max - u_min), 0, 1): 1 at (or below) u_min, 0 at (or above)
    u_max.

    Args:
        u: brightness per lane (mi.Float); u_min, u_max: the ramp's ends, u_min < u_max.

    Returns:
        mi.Float in [0, 1].
    """
    return 1.0 - dr.clip((u - u_min) * (1.0 / (u_max - u_min)), 0.0, 1.0)


def active_sets(u: mi.Float, sets: int, u_min: float, u_max: float) -> mi.Float:
    """m = floor(coverage(u) sets + 1/2), the number of sets drawn at brightness u.

    Args:
        u: brightness per lane (mi.Float); sets: the set count; u_min, u_max: the ramp's ends.

    Returns:
        An integer-valued mi.Float in {0..sets}.
    """
    return dr.floor(coverage(u, u_min, u_max) * sets + 0.5)


def hatch_mask(p: mi.Point3f, u: mi.Float, normals: Sequence[Sequence[float]], spacing: float,
               thickness: float, ramp: tuple[float, float] = (0.05, 0.9),
               projection: Projection | None = None) -> mi.Bool:
    """True where p lies within thickness/2 of a plane of one of the m(u) active sets (the linear
    ramp).

    Args:
        p: world points (mi.Point3f); u: their brightness (mi.Float).
        normals: the sets' unit plane normals (`plane_normals`).
        spacing, thickness: plane distance and line thickness (pixels with `projection`).
        ramp: the ramp's ends (u_min, u_max), as `BrightnessRange.u_range` gives them.
        projection: None: parallel world planes; given: pencils of planes through the camera.

    Returns:
        mi.Bool.
    """
    m = active_sets(u, len(normals), *ramp)
    hit = dr.zeros(mi.Bool, dr.width(p))
    for j, on_line in enumerate(line_masks(p, normals, spacing, thickness, projection)):
        hit |= on_line & (m > j)
    return hit


def line_masks(p: mi.Point3f, normals: Sequence[Sequence[float]], spacing: float, thickness: float,
               projection: Projection | None = None) -> list[mi.Bool]:
    """Per set j: True where p lies within thickness/2 of one of its planes (drawn or not).

    Args:
        p: world points (mi.Point3f); normals: the sets' unit plane normals.
        spacing, thickness: plane distance and line thickness (pixels with `projection`).
        projection: None: parallel world planes; given: pencils of planes through the camera.

    Returns:
        One mi.Bool per set.
    """
    if projection is None:
        rel, scale = mi.Vector3f(p), 1.0 / spacing
    else:
        rel, fp = projection.footprint(p)
        scale = dr.rcp(fp) * (1.0 / spacing)
    out = []
    for nj in normals:
        s = dr.dot(rel, mi.Vector3f(*nj)) * scale + 0.5
        dist = dr.abs(s - dr.floor(s) - 0.5) * spacing
        out.append(dist < 0.5 * thickness)
    return out


def coordinate_line_masks(
    s: mi.Point2f,
    depth: mi.UInt32,
    sets: int,
    angle: float,
    angle_reflected: float,
    spacing: float,
    thickness: float,
) -> list[mi.Bool]:
    """Per set j: True where the image coordinate s (pixels) lies within thickness/2 of one of its
    lines, the set's angle theta_j = angle (angle_reflected at depth > 0) + j pi / sets (canonical
    lifting).

    Args:
        s: image coordinates (mi.Point2f, pixels); depth: path depth per lane (mi.UInt32).
        sets: the set count; angle, angle_reflected: the first set's angles (degrees).
        spacing, thickness: line distance and thickness, in pixels.

    Returns:
        One mi.Bool per set.
    """
    out = []
    for j in range(sets):
        t0 = math.radians(angle) + j * math.pi / sets
        t1 = math.radians(angle_reflected) + j * math.pi / sets
        deep = depth > 0
        c = dr.select(deep, math.cos(t1), math.cos(t0))
        sn = dr.select(deep, math.sin(t1), math.sin(t0))
        x = (s.x * c + s.y * sn) * (1.0 / spacing) + 0.5
        out.append(dr.abs(x - dr.floor(x) - 0.5) * spacing < 0.5 * thickness)
    return out


def set_thresholds(sets: int, u_min: float, u_max: float) -> list[float]:
    """Set j is drawn iff u <= its threshold u_max - (j + 1/2)(u_max - u_min)/sets (where m(u) >
    j).

    Args:
        sets: the set count; u_min, u_max: the linear ramp's ends.

    Returns:
        The thresholds, one per set.
    """
    return [u_max - (j + 0.5) * (u_max - u_min) / sets for j in range(sets)]


AUTO_U_MIN = ("unused while tones applies; given u_max only: the 5% brightness quantile "
              "(unresolved: 0.05)")
AUTO_U_MAX = ("unused while tones applies; given u_min only: the 95% brightness quantile "
              "(unresolved: 0.9)")
AUTO_TONES = (
    "the scene's first-hit brightness distribution mixed with its lightness at 9 knots, unless "
    "u_min or u_max is given (unresolved: the linear ramp)"
)


def tone_params(full: str, none: str) -> tuple[Param, ...]:
    """The tone parameters of hatching and halftone: `tones`, and `u_min` / `u_max` of the linear
    ramp.

    Args:
        full: what happens at full tone, ending u_min's doc (e.g. "all sets are drawn").
        none: what happens at no tone, ending u_max's doc.

    Returns:
        (tones, u_min, u_max) Params, all auto.
    """
    return (
        Param(
            "tones",
            "floats",
            None,
            "the tone curve: brightnesses at tone 0, 1/K, .., 1 (K + 1 values)",
            auto=AUTO_TONES,
        ),
        Param(
            "u_min",
            "float",
            None,
            f"brightness at and below which {full} (a linear ramp)",
            auto=AUTO_U_MIN,
        ),
        Param(
            "u_max",
            "float",
            None,
            f"brightness at and above which {none} (a linear ramp)",
            auto=AUTO_U_MAX,
        ),
    )


class BrightnessRange:
    """Mixin of hatching and halftone: the tone of a brightness, by the tone curve `tones` (auto:
    the scene's distribution, `tone.tone_knots`) or by a linear ramp between u_min and u_max where
    either is given."""

    @property
    def uses_tones(self) -> bool:
        return self.tones is not None and self.u_min is None and self.u_max is None

    def u_range(self) -> tuple[float, float]:
        """The brightness range toned: the tone curve's ends, else (u_min, u_max) with an
        unresolved end 0.05 or 0.9 (kept 0.85 from the given one where that would invert them)."""
        if self.uses_tones:
            return self.tones[0], self.tones[-1]
        lo = 0.05 if self.u_min is None else self.u_min
        hi = 0.9 if self.u_max is None else self.u_max
        if self.u_min is None and self.u_max is not None and not hi > lo:
            lo = hi - 0.85
        if self.u_max is None and self.u_min is not None and not hi > lo:
            hi = lo + 0.85
        return lo, hi

    def toned(self, u: mi.Float) -> mi.Float:
        """1 where fully toned (dark) to 0 where untoned, by the tone curve or the linear ramp.

        Args:
            u: brightness per lane (mi.Float).

        Returns:
            mi.Float in [0, 1].
        """
        if self.uses_tones:
            return 1.0 - tone_of(u, self.tones)
        return coverage(u, *self.u_range())

    def check_u_range(self) -> None:
        """Raise StyleError for tones given with u_min/u_max, a decreasing or too short tone
        curve, or u_max <= u_min."""
        if self.tones is not None and (self.u_min is not None or self.u_max is not None):
            raise StyleError("bad value for parameter 'tones': tones and u_min/u_max are "
                             "alternatives; give one")
        if self.tones is not None and any(b < a for a, b in zip(self.tones, self.tones[1:])):
            raise StyleError(
                f"bad value {','.join(map(str, self.tones))!r} for parameter 'tones': must not "
                f"decrease"
            )
        if self.tones is not None and (len(self.tones) < 2 or not self.tones[-1] > self.tones[0]):
            raise StyleError(
                f"bad value {','.join(map(str, self.tones))!r} for parameter 'tones': at least two "
                f"brightnesses, the last above the first"
            )
        lo, hi = self.u_range()
        if not hi > lo:
            raise StyleError(f"bad value {hi:g} for parameter 'u_max': must exceed u_min = {lo:g}")

    def auto_values(self, facts) -> dict:
        """The auto tone curve, or the missing end of a linear ramp (as `Style.auto_values`).

        Args:
            facts: the style's `scene.defaults.Facts` (its brightness quantiles).

        Returns:
            {"tones": ...} with neither ramp end given; the unset one of u_min, u_max with one.
        """
        if self.u_min is None and self.u_max is None:
            return ({} if self.tones is not None
                    else {"tones": increasing(tone_knots(facts.brightness))})
        if self.u_min is not None and self.u_max is not None:
            return {}
        lo, hi = increasing(facts.brightness([0.05, 0.95]))
        if self.u_min is not None:
            lo = self.u_min
            hi = hi if hi > lo else lo + max(abs(lo), 1e-3)
        if self.u_max is not None:
            hi = self.u_max
            lo = lo if hi > lo else hi - max(abs(hi), 1e-3)
        return {k: v for k, v in (("u_min", lo), ("u_max", hi)) if self.values[k] is None}


@register_style
class Hatching(BrightnessRange, Style):
    """The hatching style (the module doc).

    Args:
        **values: its parameters (the module doc), as `Style` takes them.

    Raises:
        StyleError: a bad value, thickness >= the spacing in use, or a bad tone range.
    """

    name = "hatching"
    summary = ("cross-hatching: brightness picks how many plane sets around the view direction "
               "draw lines")
    params = (
        Param("sets", "int", 3, "number of hatching directions", low=1, high=8),
        Param(
            "spacing_px",
            "float",
            8.0,
            "distance between lines on screen (pixels, projected at each "
            "vertex's depth); used unless spacing is given",
            low=0.0,
            low_open=True,
        ),
        Param(
            "spacing",
            "float",
            None,
            "distance between planes (scene units), replacing spacing_px",
            low=0.0,
            low_open=True,
            auto="not used: lines spacing_px apart on screen",
        ),
        Param(
            "thickness",
            "float",
            None,
            "line thickness d, in the units of the spacing in use, < spacing",
            low=0.0,
            low_open=True,
            auto="0.3 * the spacing in use",
        ),
        Param(
            "angle", "float", 45.0, "rotation of the first set around the view direction (degrees)"
        ),
        *tone_params("all sets are drawn", "no set is drawn"),
        Param("line_color", "color", (0.05, 0.05, 0.08), "colour of the lines", low=0.0),
        Param("background", "color", (0.97, 0.95, 0.9), "colour between the lines", low=0.0),
        Param(
            "lift",
            "choice",
            "canonical",
            "where screen lines are evaluated: the vertex's image coordinate "
            "(canonical: LLaT's mirror-anchor map) or its own position's projection (position)",
            choices=("canonical", "position"),
        ),
        Param(
            "angle_reflected",
            "float",
            None,
            "the first set's angle at path depth > 0 (degrees)",
            auto="the same as angle",
        ),
    )
    default_inner = 16

    def __init__(self, **values):
        super().__init__(**values)
        self.set_camera((0.0, 0.0, 1.0), (0.0, 1.0, 0.0))
        self.projection = Projection()

    @property
    def pitch(self) -> float:
        """The spacing in use: `spacing` (scene units) if given, else `spacing_px` (pixels)."""
        return self.spacing_px if self.spacing is None else self.spacing

    @property
    def line_thickness(self) -> float:
        return 0.3 * self.pitch if self.thickness is None else self.thickness

    def validate(self) -> None:
        if not self.line_thickness < self.pitch:
            which = "spacing_px" if self.spacing is None else "spacing"
            raise StyleError(
                f"bad value {self.line_thickness:g} for parameter 'thickness': must be less than "
                f"{which} = {self.pitch:g}"
            )
        self.check_u_range()

    def set_camera(self, view: Sequence[float], up: Sequence[float]) -> None:
        """Orient the plane sets for a camera (`prepare` reads the scene's).

        Args:
            view: the camera's forward direction; up: its up vector.
        """
        self.view = tuple(float(x) for x in view)
        self.up = tuple(float(x) for x in up)
        self.normals = plane_normals(self.view, up, self.sets, self.angle)

    def prepare(self, scene: mi.Scene) -> None:
        self.set_camera(camera_forward(scene), camera_up(scene))
        self.projection = projection(scene)

    @property
    def wants_coordinate(self) -> bool:
        """The integrator computes Vertex.s for this style (canonical lifting of screen lines)."""
        return self.spacing is None and self.lift == "canonical"

    def _masks(self, v: Vertex) -> list:
        """Per set j: v on one of its lines (drawn or not), by the mode in use."""
        if v.s is not None and self.wants_coordinate:
            return coordinate_line_masks(
                v.s,
                v.depth,
                self.sets,
                self.angle,
                self.reflected_angle,
                self.pitch,
                self.line_thickness,
            )
        # position mode; a depth-dependent angle picks the other plane normals at depth > 0
        masks = line_masks(v.p, self.normals, self.pitch, self.line_thickness,
                           projection=self.projection if self.spacing is None else None)
        if self.reflected_angle != self.angle:
            other = line_masks(
                v.p,
                plane_normals(self.view, self.up, self.sets, self.reflected_angle),
                self.pitch,
                self.line_thickness,
                projection=self.projection if self.spacing is None else None,
            )
            masks = [dr.select(v.depth > 0, b, a) for a, b in zip(masks, other)]
        return masks

    @property
    def reflected_angle(self) -> float:
        return self.angle if self.angle_reflected is None else self.angle_reflected

    def active(self, u: mi.Float) -> mi.Float:
        """m(u), the number of sets drawn at brightness u.

        Args:
            u: brightness per lane (mi.Float).

        Returns:
            An integer-valued mi.Float in {0..sets}.
        """
        if self.uses_tones:
            return dr.minimum(dr.floor(self.toned(u) * (self.sets + 1)), self.sets)
        return active_sets(u, self.sets, *self.u_range())

    def thresholds_of_sets(self) -> list[float]:
        """Set j is drawn iff u <= its threshold (where m(u) > j)."""
        if self.uses_tones:
            return [float(tone_inverse(1.0 - (j + 1) / (self.sets + 1), self.tones))
                    for j in range(self.sets)]
        return set_thresholds(self.sets, *self.u_range())

    def apply(self, I: mi.Color3f, v: Vertex) -> mi.Color3f:
        m = self.active(brightness(I))
        line = mi.Bool(False)
        for j, on in enumerate(self._masks(v)):
            line |= on & (m > j)
        return dr.select(line, mi.Color3f(*self.line_color), mi.Color3f(*self.background))

    def step_thresholds(self, v: Vertex) -> tuple:
        """One per vertex: the threshold of the first set (the one drawn longest) whose lines cover
        v; v turns line-coloured there and stays so below it. +inf where v is on no line (g is
        constant there)."""
        masks = self._masks(v)
        out = mi.Float(dr.inf)
        for on, t in reversed(list(zip(masks, self.thresholds_of_sets()))):
            out = dr.select(on, t, out)
        return (out,)

    def curvature(self, I: mi.Color3f, v: Vertex, h: mi.Float) -> mi.Color3f:
        return mi.Color3f(0.0)  # piecewise constant in brightness: all of it is in the thresholds
