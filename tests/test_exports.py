"""Every name a module lists in `__all__` exists in it, so `from module import *` works."""
import importlib
import pkgutil

import pytest

import styletrace

MODULES = sorted(
    m.name
    for m in pkgutil.walk_packages(styletrace.__path__, "styletrace.")
    # blender/ needs bpy (tests/blender); __main__ runs the command line
    if not m.name.startswith("styletrace.blender") and not m.name.endswith("__main__")
)


@pytest.mark.parametrize("name", MODULES)
def test_every_name_in_all_exists(name):
    module = importlib.import_module(name)
    missing = [n for n in getattr(module, "__all__", ()) if not hasattr(module, n)]
    assert not missing, f"{name}.__all__ names what it does not define: {missing}"
