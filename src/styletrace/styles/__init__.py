"""Style functions g_theta and their registry.

Each style lives in a module of its own and registers itself on import; this package imports them
all, so `registry.style_names()` lists every style. Styles evaluate inside the render kernel on
Dr.Jit arrays (see `base.Style`).
"""


from styletrace.errors import StyleError
from styletrace.styles import (  # noqa: F401  (each style module registers its style on import)
    acp,
    cel,
    color_map,
    contrast,
    coordinate,
    exp_tone,
    gamma,
    gooch,
    halftone,
    hatching,
    identity,
    reinhard,
    saturation,
    sepia,
    tie_dye,
    xtoon,
)
from styletrace.styles.base import Style, Vertex, brightness
from styletrace.styles.params import Param
from styletrace.styles.registry import create, style_class, style_names

__all__ = ["Style", "Vertex", "Param", "StyleError", "brightness", "create", "style_class",
           "style_names"]
