"""The `portal` Mitsuba emitter: a light portal, a rectangle over an opening (a window) through
which the environment lights an interior. It emits nothing; styletrace's next-event estimation
samples the environment through it (kernel/portal_guide.py, docs/design/portals.md).

    <emitter type="portal">
        <transform name="to_world"> ... </transform>
    </emitter>
    {"type": "portal",
     "to_world": T().translate(c) @ T().rotate(axis, angle) @ T().scale([hx, hy, 1])}

Parameters:
- `to_world` (transform, default identity): places the rectangle as Mitsuba's `rectangle` shape
  does: the square [-1, 1]^2 of the xy-plane at z = 0, mapped by it. Its transformed +z normal
  (`normal`, by the inverse transpose as Mitsuba transforms normals) points *into the room*: the
  side whose points have the environment sampled through the portal. (Blender's area lights face
  their -Z, and a Cycles portal faces into the room along it: blender/lights.py turns that axis
  onto +z.) The transform must keep the square a rectangle of non-zero area (no shear).

What it is, for the code that guides: `center`, `edge_x` and `edge_y` (half edges: the corners
are center +- edge_x +- edge_y), `normal` (unit, into the room) as numpy float64 arrays, and
`area`, a float.

What Mitsuba sees: an emitter with no flags (not `Infinite`, which would make it the scene's
environment, which escaped rays evaluate; not `Surface`, which claims a shape; not a delta) whose
every method returns zero radiance, weight and density. Mitsuba's own integrators render a
scene with a portal as without it (tests/kernel/test_portal.py compares `path`'s renders); they
spend the share of their light samples that picks it on nothing (its `sampling_weight`, 1 by
default as every emitter's, sets that share; Mitsuba refuses 0 where it is the scene's only
emitter). styletrace's emitter selection never picks it (kernel/emitter_sampler.py).
"""
from __future__ import annotations

import numpy as np

from styletrace.errors import SceneError
from styletrace.gate import dr, mi

#: the plugin's name in scene files and dicts
NAME = "portal"
#: the largest |cos| allowed between the two edges (float rounding of a rotation is ~1e-7)
SQUARE = 1e-4


def _affine(transform) -> np.ndarray:
    return np.array(transform.matrix, dtype=np.float64).reshape(4, 4)


class PortalEmitter(mi.Emitter):
    """The `portal` emitter (module docstring).

    Args:
        props: Mitsuba properties: to_world (transform), sampling_weight (float, Mitsuba's).

    Raises:
        SceneError: a `to_world` that makes the square degenerate (zero area) or not a rectangle
            (sheared), in one line naming the value.
    """

    def __init__(self, props: mi.Properties):
        super().__init__(props)
        self.m_flags = mi.EmitterFlags.Empty
        self.id_ = props.id() or "portal"
        m = _affine(props.get("to_world", mi.ScalarTransform4f()))
        self.center = m[:3, 3].copy()
        self.edge_x, self.edge_y = m[:3, 0].copy(), m[:3, 1].copy()
        lx, ly = float(np.linalg.norm(self.edge_x)), float(np.linalg.norm(self.edge_y))
        cross = np.cross(self.edge_x, self.edge_y)
        self.area = 4.0 * float(np.linalg.norm(cross))
        if not self.area > 0.0 or not np.isfinite(self.area):
            raise SceneError(f"portal '{self.id_}': its to_world makes a rectangle of zero area "
                             f"(half edges {self.edge_x.tolist()} and {self.edge_y.tolist()})")
        cos = abs(float(self.edge_x @ self.edge_y)) / (lx * ly)
        if cos > SQUARE:
            raise SceneError(f"portal '{self.id_}': its to_world shears the square into a "
                             f"parallelogram (edges at cos {cos:.3g}, expected a rectangle)")
        # +z as Mitsuba transforms a normal, by the inverse transpose: that is edge_x x edge_y over
        # the determinant, so a mirroring to_world flips it as it flips a rectangle shape's
        sign = -1.0 if np.linalg.det(m[:3, :3]) < 0.0 else 1.0
        self.normal = sign * cross / np.linalg.norm(cross)

    def corners(self) -> np.ndarray:
        """The four corners, counter-clockwise seen from the room (4 x 3 float64)."""
        c, x, y = self.center, self.edge_x, self.edge_y
        return np.array([c - x - y, c + x - y, c + x + y, c - x + y])

    # ---- Mitsuba's interface: nothing is emitted, nothing sampled

    def sample_ray(self, time, sample1, sample2, sample3, active=True):
        return dr.zeros(mi.Ray3f), mi.Spectrum(0.0)

    def sample_direction(self, it, sample, active=True):
        return dr.zeros(mi.DirectionSample3f), mi.Spectrum(0.0)

    def pdf_direction(self, it, ds, active=True):
        return mi.Float(0.0)

    def eval_direction(self, it, ds, active=True):
        return mi.Spectrum(0.0)

    def sample_position(self, time, sample, active=True):
        return dr.zeros(mi.PositionSample3f), mi.Float(0.0)

    def pdf_position(self, ps, active=True):
        return mi.Float(0.0)

    def eval(self, si, active=True):
        return mi.Spectrum(0.0)

    def sample_wavelengths(self, si, sample, active=True):
        return dr.zeros(type(si.wavelengths)), mi.Spectrum(0.0)

    def bbox(self):
        box = mi.ScalarBoundingBox3f()
        for p in self.corners():
            box.expand(mi.ScalarPoint3f(*p))
        return box

    def to_string(self):
        return (f"PortalEmitter[center={self.center.tolist()}, edge_x={self.edge_x.tolist()}, "
                f"edge_y={self.edge_y.tolist()}, normal={self.normal.tolist()}]")


def is_portal(emitter) -> bool:
    """Whether an emitter of a scene is a `portal`.

    Args:
        emitter: an mi.Emitter (as `Scene.emitters` lists it).

    Returns:
        bool.
    """
    return isinstance(emitter, PortalEmitter)


def portals(scene: mi.Scene) -> list:
    """The scene's portals, in the order Mitsuba lists them.

    Args:
        scene: the scene.

    Returns:
        list[PortalEmitter].
    """
    return [e for e in scene.emitters() if is_portal(e)]


def register() -> None:
    """Register `portal` with Mitsuba for the active variant.

    Raises:
        RuntimeError: Mitsuba refuses the registration.
    """
    mi.register_emitter(NAME, lambda props: PortalEmitter(props))


__all__ = ["NAME", "PortalEmitter", "is_portal", "portals", "register"]
