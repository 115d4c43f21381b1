"""Where styletrace meets the engine: choosing the backend and registering the Mitsuba plugins.

    styletrace.init()                 # idempotent: pick the variant, register the plugins
    styletrace.init("cuda_ad_rgb")    # or insist on one

`jit.backend()` picks a working libLLVM and the Mitsuba variant (one the user set before is kept);
every module that imports Dr.Jit or Mitsuba when it loads calls it first (through `styletrace.gate`;
`images` itself), because Dr.Jit chooses its libLLVM at import time. `init()` does that and
registers the plugins for the active variant: the integrator `stylized`, the BSDF `styled`, the
sampler `owen_sobol` and the emitter `portal` (a light portal: kernel/portal.py). The command
line, the API entry points and the tests call `init()`; a script that loads Mitsuba XML naming
`stylized` (or `portal`) calls it before `mi.load_file`. `import styletrace` alone does neither:
it loads no Dr.Jit, no Mitsuba.
"""
from __future__ import annotations

from styletrace import jit

_registered: set[str] = set()


def init(variant: str | None = None) -> str:
    """Choose the backend (`jit.backend`), then register styletrace's Mitsuba plugins `stylized`
    and `styled`, the sampler `owen_sobol` and the emitter `portal` for the active variant, once
    per variant.

    Args:
        variant: a variant to switch to; None keeps the active one or chooses one.

    Returns:
        The active variant.

    Raises:
        BackendError: no usable backend, or a variant styles cannot run on.
    """
    active = jit.backend(variant)
    if active not in _registered:
        import mitsuba as mi

        from styletrace.kernel import owen_sobol_sampler, portal
        from styletrace.kernel.styled_bsdf import StyledBSDF
        from styletrace.scene.standalone import from_properties

        # from a scene file or dict: its `mi.render` pins the scene-relative auto values
        # (scene/standalone.py)
        mi.register_integrator("stylized", lambda props: from_properties(props))
        mi.register_bsdf("styled", lambda props: StyledBSDF(props))
        owen_sobol_sampler.register()
        portal.register()
        _registered.add(active)
    return active


__all__ = ["init"]
