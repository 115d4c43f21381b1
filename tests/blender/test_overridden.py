"""Render settings with some values replaced (`blender.overridden.Overridden`): the replaced values
are read, every other one is the scene's, the scene's settings stay as they were, and a name that is
no render setting is refused in one line."""
import bpy
import pytest
import scenes as S

from styletrace.blender.overridden import Overridden


def test_overridden_reads_through_and_refuses_unknown_names():
    S.reset(8)
    st = bpy.context.scene.styletrace
    st.seed, st.spp = 3, 12
    view = Overridden(st, seed=40)
    assert (view.seed, view.spp, st.seed) == (40, 12, 3)
    st.spp = 20  # a view, not a copy
    assert view.spp == 20
    with pytest.raises(AttributeError, match=r"^no render setting 'sed' to override"):
        Overridden(st, sed=1)
    with pytest.raises(AttributeError, match="read-only"):
        view.seed = 1
