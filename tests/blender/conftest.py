"""Fixtures of the Blender add-on's tests: skipped as a whole when `bpy` (Blender as a Python module, the
`blender` extra) cannot be imported; otherwise the add-on is registered once per session."""
import os
import sys

import pytest

sys.path.insert(0, os.path.dirname(__file__))

try:
    import bpy  # noqa: F401
except ImportError as exc:  # the reason is shown by `pytest -rs`
    pytest.skip(f"bpy is not importable ({exc}); install it with pip install 'styletrace[blender]'",
                allow_module_level=True)


@pytest.fixture(scope="session", autouse=True)
def addon():
    import styletrace.blender as sb
    sb.register()
    yield sb
    sb.unregister()
