"""Where a vertex looks the denoised expectation D up inside a kernel: `Probe`, the value that
`expectation.Field.lookup` and `Field.at` read (`expectation.at_samples` for the camera samples,
`coverage.CoverageIntegrator` for its points).
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Any


@dataclass(frozen=True)
class Probe:
    """A vertex as D is looked up for it: Dr.Jit arrays, one lane per vertex.

    Args:
        film: its film position (mi.Point2f, pixels of the crop window).
        p, n: its position (mi.Point3f) and normal (mi.Vector3f). pixel: its pixel (mi.UInt32).
        valid: the lanes (mi.Bool). near: those whose film position can be trusted (None: `valid`).
    """
    film: Any
    p: Any
    n: Any
    pixel: Any
    valid: Any
    near: Any = None


__all__ = ["Probe"]
