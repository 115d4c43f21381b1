"""Blender light units -> Mitsuba emitter parameters, so that watts in Blender give the radiance
Cycles renders (docs/blender.md, "Light units"; checked by tests/blender/test_units.py):

- point and spot, power P [W]: Cycles spreads P over the whole sphere whatever the cone, so the
  radiant intensity is I = P / (4 pi) W/sr (Mitsuba `point`/`spot` `intensity`).
- sun, strength S [W/m^2]: the irradiance on a surface facing it (`directional` `irradiance`).
- area, power P [W] over area A [m^2], one side, cosine lobe: P = pi A L, so L = P / (pi A)
  (`area` `radiance` on a rectangle or disk).
- emission shaders on meshes and the world background: their strength is already radiance.

Each conversion is one function, so that a test can break one on purpose and see the Cycles
comparison fail.
"""
from __future__ import annotations

import math


def point_intensity(power: float) -> float:
    """Radiant intensity [W/sr] of a Blender point or spot light of `power` watts.

    Args:
        power: the light's power [W].

    Returns:
        P / (4 pi).
    """
    return power / (4.0 * math.pi)


def sun_irradiance(strength: float) -> float:
    """Irradiance [W/m^2] of a Blender sun of `strength`.

    Args:
        strength: the sun's strength [W/m^2].

    Returns:
        The same value: Blender's strength is the irradiance on a surface facing the sun.
    """
    return strength


def area_radiance(power: float, area: float) -> float:
    """Radiance of a one-sided Blender area light of `power` watts and `area` square metres.

    Args:
        power: the light's power [W]. area: its area [m^2].

    Returns:
        P / (pi A), in W/(m^2 sr).
    """
    return power / (math.pi * area)


def flip_v(v):
    """Mitsuba's texture v runs from the image's top row; Blender's from its bottom row.

    Args:
        v: Blender's v (a float or a numpy array).

    Returns:
        Mitsuba's v, 1 - v.
    """
    return 1.0 - v
