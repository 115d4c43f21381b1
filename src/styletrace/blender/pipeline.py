"""From Blender's render settings to styletrace's pipeline: the scene, the integrator, the passes.

The engine (F12), the restyle operator and the XML export all go through here, so that they agree on the
scene, the style and the pass split: `styletrace render FILE.xml --seed K --pass-spp N` renders the image F12
renders with seed K and N samples per pass.
"""
from __future__ import annotations

from typing import Callable, Iterator

import numpy as np

from .. import api
from ..config.line_types import without_colours
from . import build, exporter
from .properties import integrator_values

LINE_MASK = "LineMask"
#: the image before denoising, beside the denoised Combined (as Cycles' "Noisy Image")
NOISY = "Noisy"
AOV_PASSES = {"variance": ("Variance", 3, "RGB"), "bias": ("Bias", 1, "X"), "children": ("Children", 1, "X")}


def error_passes(settings) -> bool:
    """Whether F12 adds the error AOVs: not for a recorded render (it keeps the image only), nor a denoised one
    (the variance of the noisy pixel is not the error of the denoised one: docs/denoise.md)."""
    return bool(settings.aovs and not settings.record_buffer and settings.denoise == "off")


def description(depsgraph, settings, warn: Callable[[str], None] = print) -> dict:
    return exporter.export(depsgraph, spp=settings.spp, warn=warn)


def scene(depsgraph, settings, warn: Callable[[str], None] = print):
    """The loaded `mi.Scene` of the depsgraph (`api.load_scene` checks it as it checks every scene)."""
    return api.load_scene(build.scene_dict(description(depsgraph, settings, warn)))


def integrator(settings, aovs: bool | None = None, **override):
    values = integrator_values(settings)
    values["aovs"] = settings.aovs if aovs is None else aovs
    values.update(override)
    return api.make_integrator_from(values)


def passes(sc, integ, settings) -> Iterator[api.Progress]:
    return api.passes(sc, integ, settings.spp, settings.seed, pass_spp=settings.pass_spp)


def line_mask(sc, settings, should_stop: Callable[[], bool] = lambda: False) -> np.ndarray | None:
    """Where lines are drawn, in [0, 1]: the image with white lines minus the image with black lines, with the same
    seed. Line decisions do not depend on the line colour, so everything but the lines cancels exactly; this
    costs a second render of the lines' settings (documented in docs/blender.md)."""
    images = []
    # a line type's own colour= would not follow the override: every type takes line_color for the mask
    types = {"line_types": without_colours(settings.line_types)} if settings.line_types.strip() else {}
    for colour in ("0,0,0", "1,1,1"):
        prog = None
        for prog in passes(sc, integrator(settings, aovs=False, line_color=colour, line_gradient="", **types),
                           settings):
            if should_stop():
                return None
        images.append(prog.image)
    return np.clip((images[1] - images[0]).mean(axis=2), 0.0, 1.0)
