"""The Mitsuba side: the inner path tracer, the `stylized` integrator and the built-in scenes."""
from __future__ import annotations

_registered = False


def register() -> None:
    """Register styletrace's plugins with Mitsuba (idempotent)."""
    global _registered
    if _registered:
        return
    import mitsuba as mi

    from .integrator import StylizedIntegrator
    from .styled_bsdf import StyledBSDF

    mi.register_integrator("stylized", lambda props: StylizedIntegrator(props))
    mi.register_bsdf("styled", lambda props: StyledBSDF(props))
    _registered = True
