"""The evaluated depsgraph -> a scene description: a Mitsuba scene dict whose meshes are
`mesh.Part`s and whose images are numpy arrays. `build.description_scene_dict` turns it into
Mitsuba objects in process; `xml.write` into a Mitsuba XML file with PLY meshes and EXR images.
Both start from this one description, so F12 and the exported file render the same scene.

Objects are visited through `depsgraph.object_instances`. A mesh placed once is written in world
space, one shape per material slot. A mesh that is drawn as an instance (collection instances,
particles, geometry nodes instances) becomes one `shapegroup` in its local space and one `instance`
per placement.

A shape's id carries its object's and its material's names (`kernel.asset_names.named_id`, for
the Cryptomatte passes) and their pass indices where they are not 0
(`kernel.pass_indices.shape_id`: 'shape_3__cm..._...__ob7__ma5', for the Object and Material Index
passes); the XML file keeps those ids (docs/scenes.md).
"""
from __future__ import annotations

import hashlib
import re
from typing import Callable

import numpy as np

from styletrace.blender import camera, lights, materials, mesh, world
from styletrace.kernel.asset_names import named_id
from styletrace.kernel.pass_indices import shape_id

#: the material name of a slot without a material: Cycles' default surface shader's (measured:
#: Cycles 5.0's Cryptomatte manifest names such a mesh's material so)
NO_MATERIAL = "default_surface"


def placement_key(inst) -> tuple:
    """What names one drawn placement of an object across frames: the object, or for an instance
    its instancer, the instanced object and Blender's persistent id of the instance.

    Args:
        inst: a `bpy.types.DepsgraphObjectInstance`.

    Returns:
        A tuple of strings and ints.
    """
    if inst.is_instance:
        parent = inst.parent.name if inst.parent is not None else ""
        return ("instance", parent, inst.object.name, tuple(inst.persistent_id))
    return ("object", inst.object.name)


def group_id(name: str) -> str:
    """The Mitsuba id of the shapegroup of the object `name`: its letters, digits and underscores,
    the rest as underscores (Mitsuba refuses an id with a dot, and Blender's copies are named
    'Cube.001'), and a digest of the whole name, so that two names that differ only there stay
    apart.

    Args:
        name: the object's name.

    Returns:
        The id, 'group_<name>_<8 hex digits>'.
    """
    clean = re.sub(r"[^A-Za-z0-9_]", "_", name)
    digest = hashlib.sha1(name.encode("utf-8")).hexdigest()[:8]
    return f"group_{clean}_{digest}"


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
    `placements` names, after `export`, the placement (`placement_key`) each mesh shape and
    instance of the description came from, by its key in the description.
    """
    def __init__(self, depsgraph, spp: int = 16, warn: Callable[[str], None] = print):
        self.placements: dict[str, tuple] = {}
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
        """The shape descriptions of an evaluated mesh object (world space if `matrix` is given),
        each with its pass indices in "indices" and its names in "names" (`shapes_of`)."""
        return self.shapes_of(obj, self.parts(obj, matrix))

    def parts(self, obj, matrix) -> list:
        """The `mesh.Part`s of an evaluated mesh object, one per material slot.

        Args:
            obj: the evaluated object. matrix: 4x4 to world space (None: keep local).

        Returns:
            Its parts ([] where it has no mesh or no triangles).
        """
        try:
            data = obj.to_mesh()
        except RuntimeError:
            return []
        if data is None:
            return []
        try:
            return mesh.read(data, matrix)
        finally:
            obj.to_mesh_clear()

    def shapes_of(self, obj, parts: list) -> list[dict]:
        """The shape descriptions of `obj`'s `parts` (`parts`), each with its slot's material.

        Args:
            obj: the evaluated object. parts: its parts.

        Returns:
            One "blender_mesh" description per part, its pass indices in "indices" and its
            object's and material's names in "names" (object's, material's; popped by `export`,
            dropped by the viewport).
        """
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
                "indices": (int(obj.pass_index), int(mat.pass_index) if mat is not None else 0),
                # what Cycles hashes: the object's and the material's names (their manifests)
                "names": (obj.name, mat.name if mat is not None else NO_MATERIAL),
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
                            "shapegroup": {"type": "ref", "id": group_id(key)},
                            "to_world": matrix,
                        }
                        self.placements[f"instance_{n}"] = placement_key(inst)
                        n += 1
                else:
                    for shape in self._shapes(obj, matrix):
                        key = shape_id(named_id(f"shape_{n}", *shape.pop("names")),
                                       *shape.pop("indices"))
                        desc[key] = shape
                        self.placements[key] = placement_key(inst)
                        n += 1
        for key, shapes in groups.items():
            if shapes:
                desc[group_id(key)] = {"type": "shapegroup", **{
                    _part_id(group_id(key), i, s.pop("indices"), s.pop("names")): s
                    for i, s in enumerate(shapes)}}
        env = world.convert_world(self.scene.world, self.ctx)
        if env is not None:
            desc["world"] = env
        self.ctx.flush()
        return desc


def _part_id(group: str, i: int, indices: tuple[int, int], names: tuple[str, str]) -> str:
    """The id of part i of a shapegroup: the group's id in front (an XML file's ids are one
    namespace), then its names and pass indices."""
    return shape_id(named_id(f"{group}_{i}", *names), *indices)


def export(depsgraph, spp: int = 16, warn: Callable[[str], None] = print,
           placements: dict | None = None) -> dict:
    """The scene description of an evaluated depsgraph (see the module docstring).

    Args:
        depsgraph: the evaluated depsgraph. spp: the sensor's sample count.
        warn: called with each warning line.
        placements: a dict to fill with `Exporter.placements` (the Vector pass's objects), or None.

    Returns:
        The description: a Mitsuba scene dict with `mesh.Part`s and numpy images.
    """
    exporter = Exporter(depsgraph, spp, warn)
    desc = exporter.export()
    if placements is not None:
        placements.update(exporter.placements)
    return desc
