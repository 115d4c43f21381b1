"""Every style at its defaults on every corpus scene (issue 18, point 5): the render returns, with a
finite image.

"At defaults" means the style's own parameters untouched, so the scene-relative 'auto' rules run on
each scene (the brightness pilot, screen-space spacing measured on the sensor, the light from the
camera): the corpus covers an orthographic sensor (`instances`) and a thin lens (`colours`), hidden
emitters, a light tracer's scene, media and instancing, where such rules once crashed (hatching and
halftone on an orthographic sensor: an IndexError inside mi.render). Besides every registered style:
compositions (one with a screen-space operand after another style, whose auto values come from the
pilot's per-sample view directions) and feature lines with two styles.

The scene's own Mitsuba integrator settings carry over as on the command line (`api.render`).
Renders are small (16 x 16, 1 spp, 2 children per stylized vertex) and in-process; one case per
scene renders all styles and reports every failure at once.
"""
import numpy as np
import pytest

from styletrace.frontends import api
from styletrace.styles import style_names

from . import scenes

SIZE = 16
COMPOSED = ["contrast+sepia", "sepia+hatching", "gamma+halftone"]
LINES = ["cel", "identity"]


def setups():
    """(label, render keywords): every registered style, the compositions, and --lines with two
    styles."""
    out = [(style, {"style": style}) for style in style_names()]
    out += [(style, {"style": style}) for style in COMPOSED]
    out += [(f"{style} --lines", {"style": style, "lines": True}) for style in LINES]
    return out


@pytest.mark.parametrize("name", scenes.SCENES)
def test_every_style_at_defaults_renders_a_finite_image(name, tmp_path):
    xml = str(scenes.write_scene(name, tmp_path / name))
    failures = []
    for label, kwargs in setups():
        try:
            img = api.render(xml, spp=1, inner=2, seed=1, width=SIZE, height=SIZE, **kwargs)
        except Exception as exc:  # every failure is a bug: collect them all, one line each
            # mi.render wraps a style's error in drjit.custom's RuntimeError
            while exc.__cause__ is not None:
                exc = exc.__cause__
            failures.append(f"{label}: {type(exc).__name__}: {api.first_line(exc)}")
            continue
        if img.shape[:2] != (SIZE, SIZE):
            failures.append(f"{label}: image of shape {img.shape}")
        elif not np.isfinite(img).all():
            failures.append(
                f"{label}: {int((~np.isfinite(img)).any(axis=-1).sum())} pixel(s) not finite"
            )
    assert not failures, f"{name}:\n" + "\n".join(failures)
