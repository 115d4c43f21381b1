"""Style functions g_theta and their registry.

Each style lives in a module of its own and registers itself on import; this package imports them
all, so `registry.names()` lists every style. Styles evaluate inside the render kernel on Dr.Jit
arrays (see `base.Style`).
"""
from ..jit import backend as _backend

_backend()  # Dr.Jit picks its libLLVM when first imported: choose it (and the variant) before that

from . import (acp, cel, color_map, contrast, coordinate, exp_tone, gamma, gooch, halftone, hatching,  # noqa: F401
               identity, reinhard, saturation, sepia, tie_dye, xtoon)  # (registration side effects)
from .base import Style, Vertex, brightness
from ..errors import StyleError
from .params import Param
from .registry import create, get, names

__all__ = ["Style", "Vertex", "Param", "StyleError", "brightness", "create", "get", "names"]
