"""The style interface: a style function g_theta applied to an estimate of expected radiance.

A style declares
- `name`, `summary`: registry key and one line for `styletrace styles`;
- `params`: its parameters theta (`Param`), validated on construction;
- `default_inner`: the inner sample count n it wants per evaluation (0 for closed-form styles,
  which use only the vertex and theta and never trace a child path);
- `apply(I, v)`: g_theta(I) for a radiance estimate I (mi.Color3f) at vertex `v` (`Vertex`).
  It runs inside the render kernel on Dr.Jit arrays, so it must be branch-free (dr.select, no `if`
  on array values).
- optionally `form()`: g as an affine map, a power series or a polynomial fit, which the unbiased
  estimators consume (`forms.py`).
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Any, ClassVar, Mapping

import drjit as dr
import mitsuba as mi

from .params import Param, StyleError


def brightness(I: mi.Color3f) -> mi.Float:
    """u = (r + g + b) / 3, the brightness used by every setup of the paper's supplement (S5)."""
    return (I.x + I.y + I.z) * (1.0 / 3.0)


@dataclass
class Vertex:
    """Where a style is evaluated: all fields are Dr.Jit arrays over the lanes being stylized.

    p: world position; n: shading normal (world); wo: unit direction towards the viewer or previous
    vertex; view: the camera's forward direction (the same for all lanes); depth: 0 for the first
    hit seen from the camera.
    """

    p: mi.Point3f
    n: mi.Vector3f
    wo: mi.Vector3f
    view: mi.Vector3f
    depth: mi.UInt32


class Style:
    name: ClassVar[str] = ""
    summary: ClassVar[str] = ""
    params: ClassVar[tuple[Param, ...]] = ()
    default_inner: ClassVar[int] = 8
    #: True for baselines that apply g to every child sample and average (not a function of expectation).
    per_sample: ClassVar[bool] = False

    def __init__(self, **values: Any):
        known = {p.name: p for p in self.params}
        for key in values:
            if key not in known:
                allowed = ", ".join(known) if known else "none"
                raise StyleError(f"unknown parameter '{key}' for style '{self.name}': allowed are {allowed}")
        self.values: dict[str, Any] = {}
        for p in self.params:
            self.values[p.name] = p.parse(values[p.name]) if key_in(values, p.name) else p.default
        self.validate()

    def __getattr__(self, key: str) -> Any:
        values = self.__dict__.get("values")
        if values is not None and key in values:
            return values[key]
        raise AttributeError(key)

    @property
    def closed_form(self) -> bool:
        return self.default_inner == 0

    def validate(self) -> None:
        """Checks that involve several parameters at once; raise StyleError."""

    def prepare(self, scene: mi.Scene) -> None:
        """Called once per render before the kernel is traced (e.g. to read the camera)."""

    def apply(self, I: mi.Color3f, v: Vertex) -> mi.Color3f:
        raise NotImplementedError

    def form(self):
        """g as an AffineForm, SeriesForm or PolynomialForm (see `forms`) for the unbiased estimators, or
        None where only direct application (and nothing unbiased) applies."""
        return None

    def describe(self) -> str:
        vals = ", ".join(f"{p.name}={p.show(self.values[p.name])}" for p in self.params)
        return f"{self.name}({vals})"


def key_in(values: Mapping[str, Any], key: str) -> bool:
    return key in values and values[key] is not None


@dataclass(frozen=True)
class Camera:
    """World-space frame of a scene's first sensor: position, unit forward (local +z) and up (local +y)."""

    position: tuple[float, float, float] = (0.0, 0.0, 0.0)
    forward: tuple[float, float, float] = (0.0, 0.0, 1.0)
    up: tuple[float, float, float] = (0.0, 1.0, 0.0)


def camera(scene: mi.Scene) -> Camera:
    """The frame of the scene's first sensor (Mitsuba's default frame if it has none)."""
    import numpy as np
    sensors = scene.sensors()
    if not sensors:
        return Camera()
    m = np.array(sensors[0].world_transform().matrix, dtype=np.float64).reshape(4, 4, -1)[..., 0]

    def unit(v):
        return tuple(float(x) for x in v / np.linalg.norm(v))
    return Camera(position=tuple(float(x) for x in m[:3, 3]), forward=unit(m[:3, 2]), up=unit(m[:3, 1]))


def camera_forward(scene: mi.Scene) -> tuple[float, float, float]:
    """World-space viewing direction of the scene's first sensor."""
    return camera(scene).forward


__all__ = ["Style", "Vertex", "Param", "StyleError", "brightness", "Camera", "camera", "camera_forward"]
