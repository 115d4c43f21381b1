"""The viewport's scene sync: depsgraph updates -> what to export again, and the Mitsuba objects
kept per Blender object so that a rebuilt scene reuses every unchanged one.

    sync = SceneSync()
    sync.sync(depsgraph, changes_of(depsgraph.updates))   # re-exports what changed
    sc = sync.scene(view_sensor(view, window, w, h, spp))  # reuses the rest

What each kind of edit re-exports (docs/blender.md, Viewport): an object's move, geometry or
shading: that object; a light's move or change: that light; a material: the objects using it; the
world: the world only; the view or the scene camera: nothing (only the sensor is new). The
scene's objects are walked in `depsgraph.object_instances` order with F12's keys, so the rebuilt
scene equals F12's (`exporter.Exporter.export`) and renders the same image with the same seed.
"""
from __future__ import annotations

import threading
import time
from dataclasses import dataclass, field
from typing import Any, Callable, Iterable

import bpy
import numpy as np

from styletrace.blender import build, camera, exporter, lights, world
from styletrace.blender.mesh import fits, place
from styletrace.config.choices import SAMPLER_DEFAULT
from styletrace.frontends import api
from styletrace.gate import mi

MESH_TYPES = ("MESH", "CURVE", "SURFACE", "META", "FONT")
#: ID types whose datablock belongs to objects (its users are re-exported)
DATA_TYPES = ("MESH", "CURVE", "SURFACE", "META", "FONT", "LIGHT", "VOLUME", "GREASEPENCIL")


@dataclass
class Changes:
    """What a batch of depsgraph updates touched: names of objects, object data, materials; the
    world; every material (a shared node group or an image changed); the camera; the scene (its
    render settings). `everything`: export the whole scene (the first sync)."""
    objects: set = field(default_factory=set)
    data: set = field(default_factory=set)
    materials: set = field(default_factory=set)
    world: bool = False
    all_materials: bool = False
    camera: bool = False
    settings: bool = False
    everything: bool = False


def changes_of(updates: Iterable[Any]) -> Changes:
    """The `Changes` of a batch of depsgraph updates.

    Args:
        updates: `depsgraph.updates`: items with `.id`, an ID with `id_type` (or a known class),
            `name` and `is_embedded_data`.

    Returns:
        What they touched (`everything` stays False).
    """
    out = Changes()
    for u in updates:
        kind, name = id_type(u.id), u.id.name
        if kind == "OBJECT":
            out.objects.add(name)
            if getattr(u.id, "type", "") == "CAMERA":
                out.camera = True
        elif kind in DATA_TYPES:
            out.data.add(name)
        elif kind == "MATERIAL":
            out.materials.add(name)
        elif kind == "WORLD":
            out.world = True
        elif kind == "CAMERA":
            out.camera = True
        elif kind == "SCENE":
            out.settings = True
        # an embedded node tree comes with its material's or world's own update; a node group or
        # an image may be used by any material and the world
        elif kind == "NODETREE" and not u.id.is_embedded_data or kind == "IMAGE":
            out.all_materials = out.world = True
    return out


def id_type(idb) -> str:
    """An ID's type, e.g. 'OBJECT', 'MATERIAL' (`ID.id_type`; derived from its class before
    Blender 4).

    Args:
        idb: a Blender ID (datablock).

    Returns:
        Its type; for a class not known here, the class's name in capitals.
    """
    kind = getattr(idb, "id_type", None)
    if kind:
        return kind
    t = bpy.types
    for cls, name in ((t.Object, "OBJECT"), (t.Mesh, "MESH"), (t.Light, "LIGHT"),
                      (t.Material, "MATERIAL"), (t.World, "WORLD"), (t.NodeTree, "NODETREE"),
                      (t.Image, "IMAGE"), (t.Scene, "SCENE"), (t.Camera, "CAMERA"),
                      (t.Curve, "CURVE"), (t.MetaBall, "META"), (t.Collection, "COLLECTION")):
        if isinstance(idb, cls):
            return name
    return type(idb).__name__.upper()


def view_sensor(view_matrix, window_matrix, width: int, height: int, spp: int) -> dict:
    """The Mitsuba sensor of a 3D view (`context.region_data`).

    Args:
        view_matrix: the world -> view matrix (4 x 4, `region_data.view_matrix`).
        window_matrix: the projection (4 x 4, `region_data.window_matrix`).
        width, height: the region's size in pixels (the film's).
        spp: the sampler's sample count.

    Returns:
        A `perspective` or `orthographic` sensor description, as `camera.sensor` writes one."""
    view = np.array(view_matrix, dtype=np.float64)
    proj = np.array(window_matrix, dtype=np.float64)
    # a view matrix kept in float32 (or a view rotation not quite unit) carries a scale of
    # about 1e-7, which Mitsuba's sensors refuse
    to_world = camera._unscaled_camera(np.linalg.inv(view)) @ camera.FLIP
    film = {"type": "hdrfilm", "width": int(width), "height": int(height), "pixel_format": "rgb",
            "rfilter": {"type": "box"}}
    out = {"film": film, "sampler": {"type": SAMPLER_DEFAULT, "sample_count": int(spp)}}
    a, b = proj[2, 2], proj[2, 3]
    if proj[3, 3] == 1.0:  # orthographic: x' = x / half_x + offset
        half_x, half_y = 1.0 / proj[0, 0], 1.0 / proj[1, 1]
        shift = np.eye(4)
        # the view's centre is offset by -proj[:2, 3] * half; Mitsuba's x points left
        shift[0, 3] = proj[0, 3]
        shift[1, 3] = -proj[1, 3] * half_y / half_x
        near, far = (b + 1.0) / a, (b - 1.0) / a
        out.update(type="orthographic",
                   to_world=to_world @ np.diag([half_x, half_x, 1.0, 1.0]) @ shift,
                   near_clip=max(float(near), 0.0), far_clip=float(far))
        return out
    fit_x = width >= height
    scale = proj[0, 0] if fit_x else proj[1, 1]
    fov = float(np.degrees(2.0 * np.arctan(1.0 / scale)))
    out.update(type="perspective", to_world=to_world, fov=fov, fov_axis="x" if fit_x else "y",
               near_clip=float(b / (a - 1.0)), far_clip=float(b / (a + 1.0)))
    if proj[0, 2] or proj[1, 2]:
        out["principal_point_offset_x"] = float(proj[0, 2]) / 2.0
        out["principal_point_offset_y"] = -float(proj[1, 2]) / 2.0
    return out


@dataclass
class Entry:
    """One Blender object's exported part: its Mitsuba objects (`built`, (kind, object) pairs),
    the world matrix and the datablocks it was made from; `slots`: a mesh's material slot of each
    built shape."""
    built: list
    matrix: np.ndarray
    data: str = ""
    materials: frozenset = frozenset()
    slots: tuple = ()


class SceneSync:
    """The exported scene of a viewport, kept between depsgraph updates.

    Args:
        warn: takes the export's warnings, one line each (default: print).

    `last` after each `sync`: `objects` (names re-exported, sorted), `world` (re-exported),
    `seconds`. `exported` counts every object export since creation, `moved` those of them that
    kept their Mitsuba objects: a mesh re-read with the same vertex and face counts and the same
    materials, none of them edited (a move, or a deformation), keeps its meshes, BSDFs and
    emitters, and its new vertices wait in `pending` until `place_moved` writes them (no new
    Dr.Jit registry ids: docs/design/viewport.md, "Object moves")."""

    def __init__(self, warn: Callable[[str], None] = print):
        self.warn = warn
        self.entries: dict[str, Entry] = {}   # objects placed once, by name
        self.groups: dict[str, Entry] = {}    # instanced objects, by name
        self.order: list[tuple[str, str, np.ndarray | None]] = []
        self.world_emitter: Any = None
        self.world_done = False
        self.last: dict = {}
        self.exported = 0
        self.moved = 0
        self.pending: dict[tuple[str, int], tuple[Any, Any]] = {}  # (name, i): (mi.Mesh, Part)
        self._pending_lock = threading.Lock()  # sync (main thread) and place_moved (a worker)

    def _dirty(self, name: str, entry: Entry | None, matrix, ch: Changes) -> bool:
        if entry is None or ch.everything or name in ch.objects or entry.data in ch.data:
            return True
        if matrix is not None and not np.array_equal(matrix, entry.matrix):
            return True
        return bool(entry.materials & ch.materials) or (ch.all_materials and bool(entry.materials))

    def _export(self, ex: exporter.Exporter, obj, matrix, ch: Changes,
                kept: Entry | None = None) -> Entry:
        self.exported += 1
        slots = getattr(obj, "material_slots", ())
        mats = frozenset(s.material.name for s in slots if s.material is not None)
        data = obj.data.name if obj.data is not None else ""
        if obj.type == "LIGHT":
            desc = lights.convert_light(obj.data, matrix, self.warn)
            built = [] if desc is None else [("light", _made(desc))]
            return Entry(built, matrix, data, mats)
        parts = ex.parts(obj, matrix)
        name = obj.name
        if matrix is not None:  # a placed object (an instanced one keeps no vertices pending)
            with self._pending_lock:
                for key in [k for k in self.pending if k[0] == name]:
                    del self.pending[key]
                if kept is not None and self._keeps(kept, parts, data, mats, ch):
                    self.moved += 1
                    for i, (part, (_, made)) in enumerate(zip(parts, kept.built)):
                        self.pending[(name, i)] = (made, part)
                    return Entry(kept.built, matrix, data, mats, kept.slots)
        shapes = ex.shapes_of(obj, parts)
        for s in shapes:  # the viewport writes no index or Cryptomatte passes
            s.pop("indices")
            s.pop("names")
        return Entry([("shape", build.node(s)) for s in shapes], matrix, data, mats,
                     tuple(p.slot for p in parts))

    @staticmethod
    def _keeps(kept: Entry, parts: list, data: str, mats: frozenset, ch: Changes) -> bool:
        """Whether the kept meshes take `parts` in place: the same datablock and materials, none
        edited (their BSDFs and emitters would be made alike), a part per kept mesh, each with
        its slot and vertex and face counts."""
        if ch.everything or kept.data != data or kept.materials != mats:
            return False
        if kept.materials & ch.materials or (ch.all_materials and kept.materials):
            return False
        return (len(parts) == len(kept.built) == len(kept.slots)
                and all(p.slot == slot and what == "shape" and fits(made, p)
                        for p, slot, (what, made) in zip(parts, kept.slots, kept.built)))

    def place_moved(self) -> int:
        """Write the vertices of the objects re-read since the last call (`pending`) into their
        kept meshes. Call it under Dr.Jit's lock (`viewport.TURNS`) before loading a scene of the
        kept objects: a scene loaded before from those meshes must not be traced again.

        Returns:
            How many meshes were written.
        """
        with self._pending_lock:
            moves, self.pending = list(self.pending.values()), {}
        for made, part in moves:
            place(made, part)
        return len(moves)

    def sync(self, depsgraph, changes: Changes | None = None) -> dict:
        """Export what `changes` touched (everything when None), and any object whose world
        matrix moved; forget removed objects.

        Args:
            depsgraph: the evaluated depsgraph (its object instances and the scene's world).
            changes: what the updates touched (`changes_of`); None exports everything.

        Returns:
            `last`: the names re-exported, whether the world was, the seconds taken."""
        start = time.perf_counter()
        ch = changes or Changes(everything=True)
        ex = exporter.Exporter(depsgraph, warn=self.warn)
        done: list[str] = []
        order: list[tuple[str, str, np.ndarray | None]] = []
        seen, seen_groups = set(), set()
        for inst in depsgraph.object_instances:
            obj = inst.object
            if not inst.show_self or obj.type not in MESH_TYPES + ("LIGHT",):
                continue
            matrix = np.array(inst.matrix_world, dtype=np.float64)
            name = obj.name
            if inst.is_instance and obj.type != "LIGHT":
                if name not in seen_groups:
                    seen_groups.add(name)
                    if self._dirty(name, self.groups.get(name), None, ch):
                        self.groups[name] = self._export(ex, obj, None, ch)
                        done.append(name)
                order.append(("instance", name, matrix))
            elif not inst.is_instance and name not in seen:
                seen.add(name)
                kept = self.entries.get(name)
                if self._dirty(name, kept, matrix, ch):
                    self.entries[name] = self._export(ex, obj, matrix, ch, kept)
                    done.append(name)
                order.append(("object", name, None))
        for gone in set(self.entries) - seen:
            del self.entries[gone]
            with self._pending_lock:
                for key in [k for k in self.pending if k[0] == gone]:
                    del self.pending[key]
        for gone in set(self.groups) - seen_groups:
            del self.groups[gone]
        self.order = order
        redo_world = ch.everything or ch.world or not self.world_done
        if redo_world:
            env = world.convert_world(depsgraph.scene_eval.world, ex.ctx)
            self.world_emitter = None if env is None else _made(env)
            self.world_done = True
        ex.ctx.flush()
        self.last = {"objects": sorted(done), "world": redo_world,
                     "seconds": time.perf_counter() - start}
        return self.last

    def scene_dict(self, sensor: dict) -> dict:
        """The Mitsuba scene dict of the kept objects and `sensor`, keyed and ordered as F12's.

        Args:
            sensor: a sensor description (e.g. `view_sensor`'s); `build.node` converts it.

        Returns:
            The scene dict; its Mitsuba objects are the kept ones, shared with earlier dicts (a
            moved object's meshes have their new vertices once `place_moved` wrote them).
        """
        desc: dict = {"type": "scene", "sensor": build.node(sensor)}
        n = 0
        for kind, name, matrix in self.order:
            if kind == "instance":
                if self.groups[name].built:
                    ref = {"type": "ref", "id": exporter.group_id(name)}
                    desc[f"instance_{n}"] = {"type": "instance",
                                             "to_world": mi.ScalarTransform4f(matrix.tolist()),
                                             "shapegroup": ref}
                    n += 1
                continue
            for what, made in self.entries[name].built:
                desc[f"{what}_{n}"] = made
                n += 1
        for name, entry in self.groups.items():
            if entry.built:
                desc[exporter.group_id(name)] = {"type": "shapegroup",
                                         **{f"part_{i}": m for i, (_, m) in enumerate(entry.built)}}
        if self.world_emitter is not None:
            desc["world"] = self.world_emitter
        return desc

    def scene(self, sensor: dict):
        """The loaded `mi.Scene` (`api.load_scene` checks it as F12's), moved meshes placed first
        (`place_moved`).

        Args:
            sensor: a sensor description, as for `scene_dict`.

        Returns:
            The `mi.Scene`.

        Raises:
            SceneError: a scene `api.load_scene` refuses (let through).
        """
        self.place_moved()
        return api.load_scene(self.scene_dict(sensor))


def _made(desc: dict) -> Any:
    """A description node made into its Mitsuba object once, so that later scenes reuse it."""
    return mi.load_dict(build.node(desc))


__all__ = ["Changes", "changes_of", "view_sensor", "SceneSync", "Entry"]
