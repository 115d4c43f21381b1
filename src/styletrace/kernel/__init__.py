"""The render kernel and its Mitsuba plugins: the `stylized` integrator (integrator.py; built from
a file by scene/standalone.py) and the `styled` BSDF (styled_bsdf.py), the path kernel, media,
feature lines, LLaT's tone, sample reuse and the per-render state. `styletrace.init()` registers
the plugins."""

