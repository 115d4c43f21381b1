"""Fixtures of the Blender add-on's tests. They need `bpy` (Blender as a Python module, the
`blender` extra), and bpy 5.0's compiled modules need numpy 1.x. Without both, every test module
here is left uncollected and test_availability.py skips with the reason (`pytest -rs`); otherwise
the add-on is registered once per session."""
import os
import sys

import numpy
import pytest

sys.path.insert(0, os.path.dirname(__file__))


def _unavailable() -> str | None:
    if int(numpy.__version__.split(".")[0]) >= 2:
        return (
            f"bpy needs numpy < 2 and numpy {numpy.__version__} is installed: install the blender "
            f"extra with "
            f"constraints-blender.txt, or put numpy 1.26 first on PYTHONPATH (docs/blender.md, "
            f"Tests)"
        )
    try:
        import bpy  # noqa: F401
    except ImportError as exc:
        return (
            f"bpy is not importable ({exc}); install it with pip install -c "
            f"constraints-blender.txt '.[blender]'"
        )
    return None


UNAVAILABLE = _unavailable()


def pytest_ignore_collect(collection_path, config):
    if (
        UNAVAILABLE
        and collection_path.name.startswith("test_")
        and collection_path.name != "test_availability.py"
    ):
        return True
    return None


@pytest.fixture(scope="session", autouse=True)
def addon():
    if UNAVAILABLE:
        yield None
        return
    import styletrace.blender as sb
    sb.register()
    yield sb
    sb.unregister()
