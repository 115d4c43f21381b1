"""File -> Export -> Mitsuba XML (styletrace): the evaluated scene as a Mitsuba XML file with PLY
meshes, with the render settings as its `stylized` integrator. The report names the command line
that renders the F12 image."""
from __future__ import annotations

import bpy
from bpy_extras.io_utils import ExportHelper

from styletrace.blender import animation, exporter, xml
from styletrace.blender.properties import settings_integrator_values
from styletrace.errors import StyletraceError


def command_line(path: str, settings) -> str:
    """The `styletrace render` command that renders the F12 image of the exported file.

    Args:
        path: the exported XML file. settings: the scene's styletrace settings (samples, spp,
            inner samples, seed, pass split, denoising).

    Returns:
        The command line.
    """
    denoise = f" --denoise {settings.denoise}" + (
        "" if settings.denoise == "off" or settings.denoise_quality == "high"
        else f" --denoise-quality {settings.denoise_quality}")
    if settings.denoise != "off" and settings.denoise_footprint != "pixel":
        denoise += f" --denoise-footprint {settings.denoise_footprint}"
    inner = settings.inner_samples.strip()
    # F12's counts (`f12.sampling`): Samples, and Camera samples and Inner samples where given;
    # with both of those, Samples is not used (the command line would refuse three that disagree)
    counts = "" if settings.spp and inner else f" --samples {settings.samples}"
    counts += f" --spp {settings.spp}" if settings.spp else ""
    counts += f" --inner {inner}" if inner else ""
    return (
        f"styletrace render {path}{counts} --seed {settings.seed} --pass-spp "
        f"{settings.pass_spp}{denoise}"
    )


class STYLETRACE_OT_export_xml(bpy.types.Operator, ExportHelper):
    """Export the scene as a Mitsuba XML file with PLY meshes that `styletrace render` renders"""

    bl_idname = "styletrace.export_xml"
    bl_label = "Export Mitsuba XML (styletrace)"
    filename_ext = ".xml"
    filter_glob: bpy.props.StringProperty(default="*.xml", options={"HIDDEN"})

    def execute(self, context):
        st = context.scene.styletrace
        try:
            desc = exporter.export(context.evaluated_depsgraph_get(), spp=st.samples,
                                   warn=lambda m: self.report({"WARNING"}, m))
            values = settings_integrator_values(st)
            values["aovs"] = False
            xml.write(desc, self.filepath, values)
        except (StyletraceError, OSError, ValueError) as exc:
            self.report({"ERROR"}, str(exc).strip().splitlines()[-1])
            return {"CANCELLED"}
        self.report(
            {"INFO"}, f"wrote {self.filepath}; the F12 image: "
            f"{command_line(self.filepath, animation.at_frame(st, context.scene.frame_current))}"
        )
        return {"FINISHED"}


def menu(self, context):
    """File -> Export's entry (a menu draw function).

    Args:
        self: the menu. context: Blender's context.
    """
    self.layout.operator(STYLETRACE_OT_export_xml.bl_idname, text="Mitsuba XML (styletrace)")


def register_operators():
    bpy.utils.register_class(STYLETRACE_OT_export_xml)
    bpy.types.TOPBAR_MT_file_export.append(menu)


def unregister_operators():
    bpy.types.TOPBAR_MT_file_export.remove(menu)
    bpy.utils.unregister_class(STYLETRACE_OT_export_xml)
