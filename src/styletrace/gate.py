"""Dr.Jit and Mitsuba, loaded after the backend is chosen: the one way in to the engine.

Every module that renders takes `dr` and `mi` from here:

    from styletrace.gate import dr, mi

Importing this module first picks a working libLLVM and the Mitsuba variant (`jit.backend`), since
Dr.Jit binds its libLLVM when it is first imported. `import styletrace` alone does not load it.
"""
from importlib import import_module

from styletrace.jit import backend

backend()
dr = import_module("drjit")
mi = import_module("mitsuba")

__all__ = ["dr", "mi"]
