"""The panels are generated from the style registry, and values the registry refuses come back as
one-line Blender error reports (never a traceback)."""
import bpy
import pytest
import scenes as S

from styletrace.blender import panels, properties
from styletrace.styles import registry


def test_every_style_parameter_has_a_property_and_a_row():
    S.reset(16)
    st = bpy.context.scene.styletrace
    style_enum = {i.identifier for i in st.bl_rna.properties["style"].enum_items}
    assert style_enum == set(registry.style_names())
    for name in registry.style_names():
        st.style = name
        rows = [prop for owner, prop in panels.layout_rows(st) if owner == st.params]
        assert rows == [properties.key(name, p.name) for p in registry.style_class(name).params]
        # the default shown is the registry's, in --set spelling
        for p in registry.style_class(name).params:
            value = getattr(st.params, properties.key(name, p.name))
            if isinstance(value, str):
                assert value == p.show(p.default)
    mat = bpy.data.materials.new("m")
    assert [prop for _, prop in panels.layout_rows(mat.styletrace, material=True)] == ["use_style"]
    mat.styletrace.use_style = True
    assert ("style" in [prop for _, prop in panels.layout_rows(mat.styletrace, material=True)])


def test_refused_value_is_a_one_line_error_report(tmp_path):
    S.room(16)
    s = bpy.context.scene
    s.render.engine = "STYLETRACE"
    st = s.styletrace
    st.style, st.spp, st.pass_spp = "cel", 2, 2
    st.params.cel__levels = "0.3,abc"
    with pytest.raises(RuntimeError) as info:
        bpy.ops.render.render()
    message = str(info.value).strip()
    print(message)
    assert message.startswith("Error:") and "bad value '0.3,abc' for parameter 'levels'" in message
    assert "\n" not in message and "Traceback" not in message


def test_restyle_without_buffer_reports(tmp_path):
    S.reset(16)
    with pytest.raises(RuntimeError) as info:
        bpy.ops.styletrace.restyle()
    assert str(info.value).strip().startswith("Error: no recorded buffer")
