"""The viewport's sync (`viewport_sync`): each kind of edit, seen as Blender's depsgraph updates,
re-exports only what changed (an object move: that object; a light: that light; a material: its
users; the world: none of the objects; the camera: nothing), unchanged objects keep their Mitsuba
objects, and the synced scene renders F12's image (a full export of the same depsgraph) to the bit.
The view's sensor from the region's matrices equals the scene camera's (`camera.sensor`)."""
import math

import bpy
import numpy as np
import pytest
import scenes as S

from styletrace.blender import camera, f12
from styletrace.blender.viewport import Viewport
from styletrace.blender.viewport_sync import SceneSync, changes_of, view_sensor


def image(sc, st):
    prog = None
    for prog in f12.f12_passes(sc, f12.integrator(st, aovs=False), st):
        pass
    return prog.image


EDITS = [  # (what, the edit, objects re-exported, world re-exported)
    ("object move", lambda: setattr(bpy.data.objects["Cube"].location, "x", 0.2), ["Cube"], False),
    ("light move", lambda: setattr(bpy.data.objects["area"].location, "y", -0.2), ["area"], False),
    ("light change", lambda: setattr(bpy.data.lights["sun"], "energy", 3.0), ["sun"], False),
    ("material change", lambda: bpy.data.materials["red"].node_tree.nodes["Diffuse BSDF"]
     .inputs["Color"].__setattr__("default_value", (0.8, 0.15, 0.9, 1.0)), ["Plane.002"], False),
    ("world change", lambda: bpy.data.worlds["world"].node_tree.nodes["Background"]
     .inputs["Strength"].__setattr__("default_value", 0.5), [], True),
    ("camera move", lambda: setattr(bpy.data.objects["camera"].location, "x", 0.3), [], False),
]


def test_each_edit_re_exports_what_changed_and_renders_f12s_image():
    S.room(16)
    st = bpy.context.scene.styletrace
    st.spp, st.pass_spp, st.seed, st.style = 4, 4, 2, "identity"
    sync = SceneSync()
    sync.sync(bpy.context.evaluated_depsgraph_get())
    seen = []

    def handler(scene, depsgraph):  # what view_update receives: the depsgraph with its updates
        seen.append((sync.sync(depsgraph, changes_of(depsgraph.updates)), depsgraph))

    bpy.app.handlers.depsgraph_update_post.append(handler)
    try:
        for what, edit, objects, world in EDITS:
            kept = {name: [m for _, m in e.built] for name, e in sync.entries.items()}
            seen.clear()
            edit()
            bpy.context.view_layer.update()
            assert len(seen) == 1, what
            stats, dg = seen[0]
            print(f"{what}: re-exported {stats['objects']}, world {stats['world']}, "
                  f"{stats['seconds'] * 1000:.1f} ms")
            assert stats["objects"] == objects and stats["world"] == world, what
            for name, entry in sync.entries.items():  # the others' Mitsuba objects are reused
                if name not in objects:
                    assert all(a is b for a, b in zip(kept[name], (m for _, m in entry.built)))
            dg = bpy.context.evaluated_depsgraph_get()
            synced = image(sync.scene(camera.sensor(dg.scene_eval, st.spp)), st)
            np.testing.assert_array_equal(synced, image(f12.scene(dg, st), st), err_msg=what)
    finally:
        bpy.app.handlers.depsgraph_update_post.remove(handler)


def test_viewport_restarts_without_exporting_on_camera_and_settings():
    S.room(16)
    st = bpy.context.scene.styletrace
    st.spp, st.pass_spp, st.style = 4, 4, "identity"
    dg = bpy.context.evaluated_depsgraph_get()
    vp = Viewport(draft=False)
    vp.set_sensor(camera.sensor(dg.scene_eval, st.spp))
    assert vp.update(dg, st)["kind"] == "first"
    exported = vp.sync.exported
    first = vp.session
    cam = bpy.data.objects["camera"]
    cam.location.z += 0.5
    dg = bpy.context.evaluated_depsgraph_get()
    vp.set_sensor(camera.sensor(dg.scene_eval, st.spp))  # the view through the moved camera
    assert vp.log[-1]["kind"] == "camera" and vp.session is not first
    st.spp = 8  # a render setting: new passes, nothing exported
    assert vp.update(dg, st)["kind"] == "settings"
    assert vp.sync.exported == exported
    vp.session.join(60)
    assert vp.session.error is None and vp.session.spp_done == 8
    vp.close()


@pytest.mark.parametrize("kind", ["PERSP", "PERSP_SHIFT_PORTRAIT", "ORTHO"])
def test_view_sensor_equals_the_cameras(kind):
    s = S.room(16)
    s.render.resolution_x, s.render.resolution_y = (24, 16) if kind != "PERSP_SHIFT_PORTRAIT" \
        else (12, 20)
    cam = s.camera
    if kind == "PERSP_SHIFT_PORTRAIT":
        cam.data.shift_x, cam.data.shift_y = 0.1, -0.2
    if kind == "ORTHO":
        cam.data.type, cam.data.ortho_scale = "ORTHO", 5.0
        cam.data.shift_x, cam.data.shift_y = 0.15, 0.05
    cam.rotation_euler.z += math.radians(10)
    dg = bpy.context.evaluated_depsgraph_get()
    w, h = camera.resolution(s)
    window = cam.calc_matrix_camera(dg, x=w, y=h)  # what region_data.window_matrix holds
    got = view_sensor(cam.matrix_world.inverted(), window, w, h, 4)
    want = camera.sensor(s, 4)
    assert got["type"] == want["type"]
    np.testing.assert_allclose(got["to_world"], want["to_world"], atol=1e-5)
    for key in ("fov", "principal_point_offset_x", "principal_point_offset_y"):
        if key in want:
            assert got[key] == pytest.approx(want[key], rel=1e-5, abs=1e-6), key
    assert got.get("fov_axis") == want.get("fov_axis")
    # the clip planes come back through the float32 projection matrix: with far / near = 1e4, a
    # float32 rounding (6e-8) of its entries moves them by up to about 1e4 * 6e-8 = 6e-4
    for key in ("near_clip", "far_clip"):
        assert got[key] == pytest.approx(want[key], rel=1e-3), key
