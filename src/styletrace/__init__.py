"""styletrace: stylized global illumination as a function of expectation, on Mitsuba 3.

`import styletrace` loads neither Dr.Jit nor Mitsuba. The first use of the rendering API
(`styletrace.render`, `styletrace.variant`, ...) or an explicit `styletrace.init()` picks a working
libLLVM and the JIT variant (`cuda_ad_rgb` where CUDA works, else `llvm_ad_rgb`; a variant you set
before is kept) and registers the Mitsuba plugins `stylized` and `styled` (see
`styletrace.scene.plugins`). The estimator library `styletrace.estimators` needs none of it and
runs on numpy alone.
"""
from __future__ import annotations

from styletrace.errors import (
    BackendError,
    SceneError,
    SettingsError,
    StyleError,
    StyletraceError,
    UsageError,
)
from styletrace.scene.plugins import init

__version__ = "0.1.0"

#: names served by `styletrace.frontends.api`, loaded (and the backend initialised) on first use
_API = ("render", "load_scene", "scene_dict", "make_integrator", "passes", "write_image",
        "Motion")
#: names served by `styletrace.lookdev` (module, name), loaded the same way
_LOOKDEV = {"render_buffer": "record", "restyle": "restyle", "load_buffer": "buffer", "fit": "fit",
            "Buffer": "buffer"}


def __getattr__(name: str):
    if name == "variant":
        return init()
    if name == "render":  # the render pipeline's, in process or on Ray with cluster= (api.render)
        init()
        from styletrace.frontends.api import render
        return render
    if name in _API:
        init()
        from styletrace.frontends import api
        return getattr(api, name)
    if name in _LOOKDEV:
        init()
        from importlib import import_module
        return getattr(import_module(f".lookdev.{_LOOKDEV[name]}", __name__), name)
    raise AttributeError(f"module 'styletrace' has no attribute {name!r}")


__all__ = ["init", "variant", "StyletraceError", "BackendError", "StyleError", "SettingsError",
           "SceneError", "UsageError", "__version__", *_API, *_LOOKDEV]
