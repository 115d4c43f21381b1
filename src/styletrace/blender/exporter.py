"""The evaluated depsgraph -> a scene description: a Mitsuba scene dict whose meshes are
`mesh.Part`s and whose images are numpy arrays. `build.description_scene_dict` turns it into
Mitsuba objects in process; `xml.write` into a Mitsuba XML file with PLY meshes and EXR images.
Both start from this one description, so F12 and the exported file render the same scene.

Objects are visited through `depsgraph.object_instances`. A mesh placed once is written in world
space, one shape per material slot. A mesh that is drawn as an instance (collection instances,
particles, geometry nodes instances) becomes one `shapegroup` in its local space and one `instance`
per placement.
"""
from __future__ import annotations

from typing import Callable

import numpy as np

from styletrace.blender import camera, lights, materials, mesh, world


def _material_style(material) -> dict | None:
    settings = getattr(material, "styletrace", None) if material is not None else None
    if settings is None or not settings.use_style:
        return None
    from styletrace.blender.properties import style_values
    return style_values(settings)


class Exporter:
    """The exporter of one evaluated depsgraph (`export`); each material is converted once.

    Args:
        depsgraph: the evaluated depsgraph. spp: the sensor's sample count.
        warn: called with each warning line (an unsupported light, node or camera setting).
    """
    def __init__(self, depsgraph, spp: int = 16, warn: Callable[[str], None] = print):
        self.depsgraph = depsgraph
        self.scene = depsgraph.scene_eval
        self.spp = spp
        self.ctx = materials.MaterialContext(warn)
        self.warn = warn
        self._bsdfs: dict[str, tuple[dict, dict | None]] = {}

    def _material(self, material) -> tuple[dict, dict | None]:
        key = material.name if material is not None else ""
        if key not in self._bsdfs:
            self._bsdfs[key] = materials.convert_material(
                material, self.ctx, _material_style(material)
            )
        return self._bsdfs[key]

    def _shapes(self, obj, matrix) -> list[dict]:
        """The shape descriptions of an evaluated mesh object (world space if `matrix` is given)."""
        try:
            data = obj.to_mesh()
        except RuntimeError:
            return []
        if data is None:
            return []
        try:
            parts = mesh.read(data, matrix)
        finally:
            obj.to_mesh_clear()
        shapes = []
        slots = obj.material_slots
        for part in parts:
            mat = slots[part.slot].material if part.slot < len(slots) else None
            bsdf, emitter = self._material(mat)
            shape = {
                "type": "blender_mesh",
                "part": part,
                "bsdf": bsdf,
                "name": f"{obj.name}.{part.slot}",
            }
            if emitter is not None:
                shape["emitter"] = emitter
            shapes.append(shape)
        return shapes

    def export(self) -> dict:
        desc: dict = {
            "type": "scene",
            "sensor": camera.sensor(self.scene, self.spp, warn=self.warn),
        }
        groups: dict[str, list[dict]] = {}
        n = 0
        for inst in self.depsgraph.object_instances:
            obj = inst.object
            if not inst.show_self:  # e.g. the emitter of a particle system that hides it
                continue
            matrix = np.array(inst.matrix_world, dtype=np.float64)
            if obj.type == "LIGHT":
                e = lights.convert_light(obj.data, matrix, self.warn)
                if e is not None:
                    desc[f"light_{n}"] = e
                    n += 1
            elif obj.type in ("MESH", "CURVE", "SURFACE", "META", "FONT"):
                if inst.is_instance:
                    key = obj.name
                    if key not in groups:
                        groups[key] = self._shapes(obj, None)
                    if groups[key]:
                        desc[f"instance_{n}"] = {
                            "type": "instance",
                            "shapegroup": {"type": "ref", "id": f"group_{key}"},
                            "to_world": matrix,
                        }
                        n += 1
                else:
                    for shape in self._shapes(obj, matrix):
                        desc[f"shape_{n}"] = shape
                        n += 1
        for key, shapes in groups.items():
            if shapes:
                desc[f"group_{key}"] = {
                    "type": "shapegroup",
                    **{f"part_{i}": s for i, s in enumerate(shapes)},
                }
        env = world.convert_world(self.scene.world, self.ctx)
        if env is not None:
            desc["world"] = env
        self.ctx.flush()
        return desc


def export(depsgraph, spp: int = 16, warn: Callable[[str], None] = print) -> dict:
    """The scene description of an evaluated depsgraph (see the module docstring).

    Args:
        depsgraph: the evaluated depsgraph. spp: the sensor's sample count.
        warn: called with each warning line.

    Returns:
        The description: a Mitsuba scene dict with `mesh.Part`s and numpy images.
    """
    return Exporter(depsgraph, spp, warn).export()
