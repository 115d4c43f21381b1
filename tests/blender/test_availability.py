"""Whether the Blender tests can run here: skipped with the reason when they cannot
(conftest.UNAVAILABLE)."""
import pytest
from conftest import UNAVAILABLE


def test_bpy_is_usable():
    if UNAVAILABLE:
        pytest.skip(UNAVAILABLE)
    import bpy
    assert bpy.app.version >= (4, 2, 0)
    # a TypeError unless the add-on registered its engine
    bpy.context.scene.render.engine = "STYLETRACE"
    assert bpy.context.scene.render.engine == "STYLETRACE"
