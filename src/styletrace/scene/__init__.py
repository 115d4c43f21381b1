"""Scenes above the kernel: built-in ones (`builtin`), loading a scene source (`loading`) and a
scene file as its author meant it (`xml_file`), the scene-relative `auto` style values (`defaults`:
a pilot of the path kernel), the `stylized` plugin as Mitsuba builds it from a file (`standalone`),
registering the plugins (`plugins`: `styletrace.init`) and the checks of render arguments
(`arguments`). The scene graph the kernel binds is `kernel.scene_graph`."""
