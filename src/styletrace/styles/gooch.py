"""gooch: cool-to-warm shading for technical illustration, in closed form (supplement S5.6), after
Gooch, Gooch, Shirley, Cohen, "A Non-Photorealistic Lighting Model for Automatic Technical
Illustration" (1998).

Parameters
- light_dir (vector, default auto): direction towards the light; auto: normalize(up - 0.3 forward)
- k_d (colour, default 0.8,0.8,0.8): the object's diffuse colour
- blue (colour, default 0,0,0.55), yellow (colour, default 0.3,0.3,0): the cool and warm tones
- alpha (float, default 0.25, >= 0), beta (float, default 0.5, >= 0): k_d's share in each tone

g = t (yellow + beta k_d) + (1 - t) (blue + alpha k_d), t = (1 + n.l) / 2, n the shading normal
facing the viewer; g ignores the estimate. Rationale: docs/design/closed_form_styles.md.
"""
from __future__ import annotations

import math

from styletrace.gate import dr, mi
from styletrace.styles.base import Param, Style, Vertex, camera, light_from_camera
from styletrace.styles.registry import register_style


def unit(v) -> tuple[float, float, float]:
    """v normalised.

    Args:
        v: a non-zero 3-vector (a sequence of numbers).

    Returns:
        v / |v| as a tuple.
    """
    n = math.sqrt(sum(x * x for x in v))
    return tuple(x / n for x in v)


def facing(n: mi.Vector3f, wo: mi.Vector3f) -> mi.Vector3f:
    """Unit shading normal flipped to the side of `wo` (n.wo >= 0 after the flip).

    Args:
        n: shading normals (mi.Vector3f, any length); wo: directions towards the viewer.

    Returns:
        mi.Vector3f, unit.
    """
    n = dr.normalize(n)
    return dr.select(dr.dot(n, wo) < 0, -n, n)


AUTO_LIGHT = "the camera's up vector tilted towards the camera, normalize(up - 0.3 forward)"
#: the light of a style never prepared on a scene (Mitsuba's default camera would give 0,1,-0.3)
FALLBACK_LIGHT = (0.0, 1.0, 0.3)


class CameraLight:
    """Mixin of gooch and xtoon: light_dir 'auto' follows the camera (see gooch's reference
    block)."""

    def light(self) -> tuple[float, float, float]:
        """The unit light direction in use: light_dir, else the prepared camera's, else
        FALLBACK_LIGHT."""
        if self.light_dir is not None:
            return unit(self.light_dir)
        return unit(self.__dict__.get("camera_light", FALLBACK_LIGHT))

    def read_light(self, scene: mi.Scene) -> None:
        """Keep the scene camera's auto light (`light_from_camera`) for an auto light_dir.

        Args:
            scene: the scene about to be rendered.
        """
        self.camera_light = light_from_camera(camera(scene))

    def auto_values(self, facts) -> dict:
        """The auto light_dir, pinned from the camera (as `Style.auto_values`).

        Args:
            facts: the style's `scene.defaults.Facts` (its `camera`).

        Returns:
            {"light_dir": ...}, or {} where light_dir is given.
        """
        return ({} if self.light_dir is not None
                else {"light_dir": light_from_camera(facts.camera)})


@register_style
class Gooch(CameraLight, Style):
    name = "gooch"
    summary = ("Gooch cool-to-warm shading from a user light direction, closed form "
               "(Gooch et al. 1998)")
    params = (
        Param(
            "light_dir", "vector", None, "direction towards the light (normalised)", auto=AUTO_LIGHT
        ),
        Param("k_d", "color", (0.8, 0.8, 0.8), "diffuse colour of the object", low=0.0),
        Param("blue", "color", (0.0, 0.0, 0.55), "cool tone k_blue", low=0.0),
        Param("yellow", "color", (0.3, 0.3, 0.0), "warm tone k_yellow", low=0.0),
        Param("alpha", "float", 0.25, "share of k_d in the cool tone", low=0.0),
        Param("beta", "float", 0.5, "share of k_d in the warm tone", low=0.0),
    )
    default_inner = 0

    def tones(self) -> tuple[tuple[float, ...], tuple[float, ...]]:
        """(k_cool, k_warm) as Python tuples."""
        cool = tuple(b + self.alpha * k for b, k in zip(self.blue, self.k_d))
        warm = tuple(y + self.beta * k for y, k in zip(self.yellow, self.k_d))
        return cool, warm

    def prepare(self, scene: mi.Scene) -> None:
        self.read_light(scene)

    def apply(self, I: mi.Color3f, v: Vertex) -> mi.Color3f:
        n = facing(v.n, v.wo)
        t = (1.0 + dr.dot(n, mi.Vector3f(*self.light()))) * 0.5
        cool, warm = self.tones()
        return dr.lerp(mi.Color3f(*cool), mi.Color3f(*warm), t)
