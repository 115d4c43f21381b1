"""styletrace: stylized global illumination as a function of expectation, on Mitsuba 3.

Importing the package chooses a JIT variant (see `styletrace.jit`) and registers the Mitsuba plugins.
The estimator library `styletrace.estimators` needs neither and can be imported on its own.
"""
from __future__ import annotations

__version__ = "0.1.0"

from .jit import BackendError, select_variant

variant = select_variant()

from .render import register as _register  # noqa: E402  (needs the variant set above)

_register()

from .api import render  # noqa: E402

__all__ = ["render", "variant", "BackendError", "__version__"]
