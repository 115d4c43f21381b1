"""The style panels, drawn from the registries: Render Properties -> styletrace (and its
Advanced sampling sub-panel), Material Properties -> styletrace style; View Layer Properties ->
Passes (the data passes, Cycles' switches). `layout_rows` lists what a
panel shows (the same walk as `draw`), so the layout can be checked and documented headless, where
Blender draws no UI."""
from __future__ import annotations

import bpy

from styletrace.blender.properties import key
from styletrace.styles import registry

RENDER_ROWS = (
    "estimator",
    "stylize",
    "stylize_depth",
    "lines",
    "line_mode",
    "line_types",
    "reuse",
    "samples",
    "max_depth",
    "seed",
    "aovs",
    "record_buffer",
    "denoise",
    "denoise_quality",
    "denoise_footprint",
    "temporal_reuse",
    "firefly",
    "firefly_k",
)
#: the sub-panel Advanced sampling (closed by default): the split of Samples, given by hand
ADVANCED_ROWS = ("spp", "inner_samples", "pass_spp", "sampler")


def style_rows(settings) -> list[tuple[object, str]]:
    """(owner, property name) of the style selector and the chosen style's parameters.

    Args:
        settings: a SceneSettings or MaterialSettings.

    Returns:
        The rows, in drawing order.
    """
    rows = [(settings, "style")]
    rows += [
        (settings.params, key(settings.style, p.name))
        for p in registry.style_class(settings.style).params
    ]
    return rows


def layout_rows(settings, material: bool = False,
                advanced: bool = False) -> list[tuple[object, str]]:
    """What a panel shows, in order (the same walk as `draw`).

    Args:
        settings: the scene's or a material's styletrace settings.
        material: the material panel (its Style this material switch, inner samples, estimator).
        advanced: the render panel's Advanced sampling sub-panel (ADVANCED_ROWS).

    Returns:
        (owner, property name) per row.
    """
    if material:
        rows = [(settings, "use_style")]
        return rows + (style_rows(settings) + [(settings, "inner_samples"), (settings, "estimator")]
                       if settings.use_style else [])
    if advanced:
        return [(settings, name) for name in ADVANCED_ROWS]
    return style_rows(settings) + [(settings, name) for name in RENDER_ROWS]


def samples_used(settings) -> bool:
    """Whether Samples sets the render's cost: not where Camera samples and Inner samples are both
    given (`f12.job`), which the panel shows by greying it out.

    Args:
        settings: the scene's styletrace settings.

    Returns:
        False where both are given, else True.
    """
    return not (settings.spp and settings.inner_samples.strip())


def dump(settings, material: bool = False, advanced: bool = False) -> list[str]:
    """The panel as text, one row each: label, value and Blender property type (docs/blender.md
    shows it next to a screenshot: `bpy` as a module draws no UI).

    Args:
        settings, material, advanced: as `layout_rows`'s.

    Returns:
        The lines.
    """
    lines = []
    for owner, name in layout_rows(settings, material, advanced):
        prop = owner.bl_rna.properties[name]
        value = getattr(owner, name)
        if prop.type == "FLOAT" and getattr(prop, "array_length", 0):
            value = "(" + ", ".join(f"{v:g}" for v in value) + ")"
        elif isinstance(value, float):
            value = f"{value:g}"
        lines.append(
            f"{prop.name:<24} {str(value)!s:<28} "
            f"[{prop.type.lower()}{'/' + prop.subtype.lower() if prop.subtype != 'NONE' else ''}]"
        )
    return lines


def _draw(layout, rows):
    for owner, name in rows:
        if name == "samples" and not samples_used(owner):
            row = layout.row()
            row.active = False  # Camera samples and Inner samples set the cost
            row.prop(owner, name)
        else:
            layout.prop(owner, name)


class EnginePanel:
    """What every styletrace panel of the Properties editor shares: its place and its engine (a
    mixin before `bpy.types.Panel`)."""
    bl_space_type = "PROPERTIES"
    bl_region_type = "WINDOW"
    COMPAT_ENGINES = {"STYLETRACE"}

    @classmethod
    def poll(cls, context):
        return context.engine in cls.COMPAT_ENGINES


class STYLETRACE_PT_render(EnginePanel, bpy.types.Panel):
    bl_label = "styletrace"
    bl_context = "render"

    def draw(self, context):
        self.layout.use_property_split = True
        st = context.scene.styletrace
        _draw(self.layout, layout_rows(st))
        if st.record_buffer:
            self.layout.operator("styletrace.restyle")


class STYLETRACE_PT_render_advanced(EnginePanel, bpy.types.Panel):
    bl_label = "Advanced sampling"
    bl_context = "render"
    bl_parent_id = "STYLETRACE_PT_render"
    bl_options = {"DEFAULT_CLOSED"}

    def draw(self, context):
        self.layout.use_property_split = True
        _draw(self.layout, layout_rows(context.scene.styletrace, advanced=True))


class STYLETRACE_PT_material(EnginePanel, bpy.types.Panel):
    bl_label = "styletrace style"
    bl_context = "material"

    @classmethod
    def poll(cls, context):
        return context.engine in cls.COMPAT_ENGINES and context.material is not None

    def draw(self, context):
        self.layout.use_property_split = True
        _draw(self.layout, layout_rows(context.material.styletrace, material=True))


def pass_rows(view_layer) -> list[tuple[object, str]]:
    """(owner, property name) of the view layer's data pass switches the engine reads: Cycles'
    own (`f12.switches`: the data passes', then Cryptomatte's), so a scene keeps its passes when
    it changes engine.

    Args:
        view_layer: the `bpy.types.ViewLayer`.

    Returns:
        The rows, in drawing order.
    """
    from styletrace.blender.f12 import switch, switches
    rows = (switch(view_layer, prop) for _, prop in switches())
    return [row for row in rows if row is not None]


class STYLETRACE_PT_passes(EnginePanel, bpy.types.Panel):
    bl_label = "Passes"
    bl_context = "view_layer"

    def draw(self, context):
        self.layout.use_property_split = True
        column = self.layout.column(heading="Data")
        for owner, name in pass_rows(context.view_layer):
            column.prop(owner, name)


CLASSES = (STYLETRACE_PT_render, STYLETRACE_PT_render_advanced, STYLETRACE_PT_material,
           STYLETRACE_PT_passes)


def register_panels():
    for cls in CLASSES:
        bpy.utils.register_class(cls)


def unregister_panels():
    for cls in reversed(CLASSES):
        bpy.utils.unregister_class(cls)
