"""Material previews (the preview ball of Material Properties, material icons) with the styletrace
engine.

Blender renders its own preview scene (ball, floor, two area lights, its world) at the preview's
size and calls the engine with `is_preview` set. The engine renders it with `settings`: the
material's own style (its styletrace panel) on an `identity` render style, a small fixed budget, and
none of F12's extras. A preview leaves the user's last render alone (the restyle buffer, the
engine's `LAST`), and reports nothing to Blender (`report`): docs/blender.md, Material preview.
"""
from __future__ import annotations

import sys
from typing import Any

from styletrace.blender.overridden import Overridden

#: the preview's budget: samples, paths per pixel (on the identity render style a camera sample
#: draws one path), and camera samples per pass (Blender stops a preview between passes when the
#: material changes under it)
SAMPLES = 16
PASS_SPP = 4
SEED = 0


def settings(scene_settings: Any) -> Overridden:
    """The render settings of a preview: `scene_settings` (the preview scene's own, defaults) with
    the identity style, `SAMPLES` samples (camera samples auto) at `PASS_SPP` per pass, seed `SEED`,
    and no lines, denoising, error passes, recorded buffer or reuse.

    Args:
        scene_settings: the preview scene's styletrace render settings.
    Returns:
        An `Overridden` view of them.
    """
    return Overridden(
        scene_settings, style="identity", inner_samples="", estimator="direct", samples=SAMPLES,
        spp=0, pass_spp=PASS_SPP, seed=SEED, lines=False, denoise="off", aovs=False,
        record_buffer=False, reuse="off",
    )


def report(kinds: set, message: str) -> None:
    """A preview's report: an error is printed to stderr, a warning dropped (they name the preview
    scene's own floor nodes). No error goes to Blender: an error report sets Blender's global
    break flag, which would cancel an F12 render running beside the preview.

    Args:
        kinds: Blender's report kinds ({"ERROR"}, {"WARNING"}, ...). message: the line.
    """
    if "ERROR" in kinds:
        print(f"styletrace preview: {message}", file=sys.stderr)
