"""The Mitsuba plugins: the path kernel, the `stylized` integrator, the `styled` BSDF, the integrator's
settings and estimator registry, and the built-in scenes. `styletrace.init()` registers the plugins."""
from ..jit import backend as _backend

_backend()  # Dr.Jit picks its libLLVM when first imported: choose it (and the variant) before that
