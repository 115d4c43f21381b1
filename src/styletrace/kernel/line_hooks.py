"""Where the `stylized` integrator meets its feature lines: the camera sample's own lines, decided
before anything else is traced for it (edge 0, LLaT's lifted lines), and the hook each walk or
bounce carries.

A line on the camera ray replaces the camera sample; walks and bounces carry the line state of the
vertex they leave (`line_states`, one per stylized level) and end where a line absorbs them. With
`lines` off no line code is traced. Each function takes the integrator (kernel/integrator.py) bound
to a scene and `stylize`, its trace of the camera ray, called for the lanes where no line fired.
Design: docs/design/feature_lines.md.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from styletrace.config import settings as S
from styletrace.gate import dr, mi
from styletrace.kernel.lifted_lines import compose_sample


def line_problem(settings: S.Settings, media: bool) -> str | None:
    """Why `settings`' lines cannot be drawn in a scene: line_mode lifted with line_depth > 1 where
    there are participating media (its auxiliary paths know no media).

    Args:
        settings: the integrator's settings. media: the scene has participating media.

    Returns:
        The message, or None.
    """
    lines = settings.lines
    if media and lines is not None and lines.mode == "lifted" and lines.depth > 1:
        return (f"bad value {lines.depth} for 'line_depth' in a scene with participating media: "
                "line_mode lifted detects lines on the camera ray only there (line_depth 1)")
    return None


def walk_lines(integ, level: int):
    """The lines hook of a walk or bounce that leaves the level-`level` vertex.

    Args:
        integ: the integrator, bound to a scene.
        level: the stylized level (-1: the camera's first vertex, where first_object_hit's camera
            walk starts).

    Returns:
        (the integrator's Lines, that vertex's LineState), or None with lines off.
    """
    if integ.lines is None:
        return None
    return integ.lines, integ.line_states[level]


@dataclass
class CameraSample:
    """What a line hook needs of the camera sample beyond its traced ray.

    Args:
        ray: the camera ray with its differentials (mi.RayDifferential3f, scaled by Mitsuba).
        spp: the camera samples per pixel those differentials were scaled for.
        medium: the camera's medium (mi.MediumPtr or None).
    """

    ray: Any
    spp: int
    medium: Any


def camera_edge(integ, stylize, scene, sampler, camera: CameraSample, ray, active):
    """Edge 0: a feature line on the camera ray replaces the pixel sample (lines.py); the other
    lanes are stylized, their walks starting from the camera's line state.

    Args:
        integ, stylize: the bound integrator and its trace of the camera ray.
        scene, sampler: the scene and the lanes' random streams.
        camera, ray: the camera sample, and its ray as mi.Ray3f.
        active: the camera lanes (mi.Bool).

    Returns:
        (value, valid, AOVs) of the camera sample.
    """
    seen, state = integ.lines.camera(scene, sampler, camera.ray, camera.spp, active)
    # the camera ray's first hit: where first_object_hit's walk starts and the
    # first_hit/first_n_hits vertex
    integ.line_states = {-1: state, 0: state}
    live = active & ~seen.fired if integ.line_short_circuit else active
    value, valid, aovs = stylize(scene, sampler, ray, live, camera.medium)
    return dr.select(seen.fired, seen.color, value), valid | seen.fired, aovs


def lifted(integ, stylize, scene, sampler, camera: CameraSample, ray, active):
    """line_mode lifted (LLaT Eq. 34): each line type's auxiliary pairs are tested for the camera
    sample (its film point and lens sample kept); the first type in priority order that fires gives
    the sample its colour, and L is traced only where none fired.

    Args:
        integ, stylize: the bound integrator and its trace of the camera ray.
        scene, sampler: the scene and the lanes' random streams.
        camera, ray: the camera sample, and its ray as mi.Ray3f.
        active: the camera lanes (mi.Bool).

    Returns:
        (value, valid, AOVs) of the camera sample.
    """
    bound = integ.lifted
    s, aperture = bound.conditioning(camera.ray)
    fired = bound.fired(s, sampler, active, aperture)
    any_fired = mi.Bool(False)
    for f in fired:
        any_fired |= f
    value, valid, aovs = stylize(scene, sampler, ray, active & ~any_fired, camera.medium)
    value = compose_sample(fired, [mi.Color3f(*t.color) for t in bound.types], value)
    return value, valid | any_fired, aovs
