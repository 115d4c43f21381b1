"""The error AOVs of a camera sample (`aovs=True`): the film channels that `pipeline.passes` turns
into each pixel's variance, its predicted direct-application bias and its children
(docs/adaptive.md)."""
from __future__ import annotations

from styletrace.gate import dr, mi

#: the film channels of `aovs=True`: the sample's squared value per channel, the predicted bias,
#: the children
AOV_NAMES = ("sq.R", "sq.G", "sq.B", "bias", "children")


def has_error_aovs(integrator) -> bool:
    """Whether an integrator's AOVs are the error AOVs (its other AOVs: light groups' Combined).

    Args:
        integrator: any Mitsuba integrator.

    Returns:
        bool.
    """
    return AOV_NAMES[0] in integrator.aov_names()


def error_aovs(value, stats: list) -> list:
    """One camera sample's AOVs in AOV_NAMES' order: its value squared per channel (the film's
    average of it gives the pixel's second moment), and at the first stylized vertex the Eq. 21
    bias prediction and the number of children.

    Args:
        value: the camera sample's value (mi.Color3f).
        stats: the (lanes, AdaptiveDirect.stats) of each style slot at the first stylized vertex.

    Returns:
        Five mi.Float: sq.R, sq.G, sq.B, bias, children.
    """
    bias, children = mi.Float(0.0), mi.Float(0.0)
    for lanes, st in stats:
        bias = dr.select(lanes, st["bias"], bias)
        children = dr.select(lanes, st["children"], children)
    return [value.x * value.x, value.y * value.y, value.z * value.z, bias, children]
