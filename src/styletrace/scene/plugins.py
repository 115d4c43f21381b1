"""The one place where styletrace meets the engine: choosing the backend and registering the
plugins.

    styletrace.init()                 # idempotent: pick the variant, register `stylized` and `styled`
    styletrace.init("cuda_ad_rgb")    # or insist on one

`jit.backend()` picks a working libLLVM and the Mitsuba variant; a variant the user set before is
kept. Every styletrace module that imports Dr.Jit or Mitsuba when it loads calls it first (the
`styles`, `kernel` and `scene` packages, `assets.scenes`, `api`, `images`), because Dr.Jit chooses
its libLLVM at import time. `init()` does that and registers the plugins for the active variant. The
command line, the API entry points and the tests call `init()`; a script that loads Mitsuba XML
naming `stylized` calls it before `mi.load_file`. `import styletrace` alone does neither: it loads
no Dr.Jit, no Mitsuba.
"""
from __future__ import annotations

from styletrace import jit

_registered: set[str] = set()


def init(variant: str | None = None) -> str:
    """`backend(variant)`, then register styletrace's Mitsuba plugins for it (idempotent)."""
    active = jit.backend(variant)
    if active not in _registered:
        import mitsuba as mi

        from styletrace.kernel.styled_bsdf import StyledBSDF
        from styletrace.scene.standalone import from_properties

        # from a scene file or dict: its `mi.render` pins the scene-relative auto values
        # (scene/standalone.py)
        mi.register_integrator("stylized", lambda props: from_properties(props))
        mi.register_bsdf("styled", lambda props: StyledBSDF(props))
        _registered.add(active)
    return active


__all__ = ["init"]
