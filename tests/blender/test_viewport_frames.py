"""Frames in Rendered shading (issue 47). The viewport renders every frame with the Seed setting
(not Render Animation's `animation.frame_seed`): scrubbing the timeline over a still scene starts
nothing and the image on screen stays the same, bit for bit; frames seen through an animated
camera start sessions (each showing the image before carried to its view) that compile no kernel
(Dr.Jit's kernel history: every launch an in-memory cache hit, as test_viewport_seed.py reads it);
an animated object still moves, rendered with the same seed, and its moves (keyframed or plain)
compile no kernel either: the moved mesh keeps its Mitsuba objects (and so Dr.Jit's registry ids,
which Dr.Jit's code for method calls depends on), and renders as a fresh export of it would."""
import gc

import bpy
import drjit as dr
import numpy as np
import scenes as S

from styletrace.blender import camera
from styletrace.blender.viewport import Viewport


def room():
    S.room(32)
    st = bpy.context.scene.styletrace
    st.style, st.seed, st.denoise, st.spp, st.pass_spp = "cel", 0, "auto", 4, 2
    return st


def start(st, frame: int | None = 1) -> Viewport:
    """A viewport through the scene camera at `frame` (None: the current one), its first session
    run to its end."""
    if frame is not None:
        bpy.context.scene.frame_set(frame)
    vp = Viewport(start=False, clock=lambda: 0.0)
    dg = bpy.context.evaluated_depsgraph_get()
    vp.set_sensor(camera.sensor(dg.scene_eval, st.samples))
    vp.update(dg, st)
    finish(vp)
    return vp


def update(vp, st, frame: int) -> dict:
    """Go to `frame` and hand the viewport the depsgraph, as Blender's view_update does."""
    bpy.context.scene.frame_set(frame)
    return vp.update(bpy.context.evaluated_depsgraph_get(), st)


def finish(vp) -> np.ndarray:
    s = vp.session
    while not s.done:
        s.schedule.step()
    assert s.error is None
    return s.latest()[0]


def compiled_kernels() -> tuple[list, int]:
    """The kernels launched since the last call that were not in-memory cache hits, and how many
    were launched."""
    launches = [k for k in dr.kernel_history() if "cache_hit" in k]
    return [(k["hash"], k["operation_count"], k["size"]) for k in launches
            if not k["cache_hit"] or k["cache_disk"]], len(launches)


def test_scrubbing_a_still_scene_starts_nothing_and_keeps_its_image():
    st = room()
    vp = start(st)
    shown, session = vp.session.latest()[0], vp.session
    dr.set_flag(dr.JitFlag.KernelHistory, True)
    try:
        dr.kernel_history()
        for frame in (2, 5, 3, 1):
            assert update(vp, st, frame)["kind"] == "none"
            assert vp.session is session
            assert np.array_equal(finish(vp), shown)
        assert compiled_kernels() == ([], 0)
    finally:
        dr.set_flag(dr.JitFlag.KernelHistory, False)
        vp.close()


def test_frames_through_an_animated_camera_compile_nothing():
    """Each frame's session compiles nothing. Dr.Jit compiles every live Mitsuba object of a
    class into a kernel's calls (docs/design/viewport.md, "Garbage and Dr.Jit's registry"), so
    objects of earlier tests or of the first session, freed by the garbage collector at its own
    time, would change the kernels' code while this test runs: the garbage is collected before
    each frame, as the viewport collects it between sessions, and one frame settles it first."""
    st = room()
    cam = bpy.data.objects["camera"]
    cam.keyframe_insert("location", frame=1)
    cam.location.x += 0.5
    cam.keyframe_insert("location", frame=5)
    vp = start(st)
    first = vp.session.latest()[0]
    dr.set_flag(dr.JitFlag.KernelHistory, True)
    try:
        for k, frame in enumerate((4, 3, 5, 2)):
            gc.collect()
            dr.kernel_history()  # reading it empties it
            update(vp, st, frame)
            # view_draw through the camera: the region's view moved
            vp.set_sensor(camera.sensor(bpy.context.evaluated_depsgraph_get().scene_eval,
                                        st.samples))
            vp.session.schedule.step()
            assert vp.session.latest()[1].startswith("reprojected")
            image = finish(vp)
            compiled, launched = compiled_kernels()
            assert launched and (k == 0 or not compiled), (frame, compiled)
            assert not np.array_equal(image, first)
    finally:
        dr.set_flag(dr.JitFlag.KernelHistory, False)
        vp.close()


def animated_cube_room():
    """The room, its cube keyframed from frame 1 to 0.6 to the left at frame 5, and a viewport
    at frame 1 (`start`): (settings, viewport)."""
    st = room()
    cube = bpy.data.objects["Cube"]
    cube.keyframe_insert("location", frame=1)
    cube.location.x -= 0.6
    cube.keyframe_insert("location", frame=5)
    return st, start(st)


def test_an_animated_object_moves_with_the_same_seed():
    st, vp = animated_cube_room()
    shown, before = vp.session.latest()[0], vp.session.surfaces.depth
    try:
        assert update(vp, st, 5)["kind"] == "objects"
        image, now = finish(vp), vp.session
        assert now.values["seed"] == st.seed == 0
    finally:
        vp.close()
    # what the view sees changed where the cube was and where it is, and the image with it
    moved = np.abs(now.surfaces.depth - before) > 0.1
    assert 20 <= moved.sum() <= 0.5 * moved.size
    assert np.abs(image - shown)[moved].mean() > 0.05


def test_object_moves_compile_nothing_and_render_as_a_fresh_export():
    st, vp = animated_cube_room()
    cube = bpy.data.objects["Cube"]
    kept = [made for _, made in vp.sync.entries["Cube"].built]
    images = [vp.session.latest()[0]]
    dr.set_flag(dr.JitFlag.KernelHistory, True)
    try:
        for step in (3, 5, 2, "plain", "plain"):
            dr.kernel_history()  # reading it empties it
            if step == "plain":  # a move by hand, the animation gone
                cube.animation_data_clear()
                cube.location.x += 0.25
                cube.location.y -= 0.1
                entry = vp.update(bpy.context.evaluated_depsgraph_get(), st)
            else:
                entry = update(vp, st, step)
            assert entry["kind"] == "objects" and entry["objects"] == ["Cube"], (step, entry)
            images.append(finish(vp))
            compiled, launched = compiled_kernels()
            assert launched and not compiled, (step, compiled)
            assert not np.array_equal(images[-1], images[-2]), step
        assert [made for _, made in vp.sync.entries["Cube"].built] == kept
        assert vp.sync.moved == 5 and not vp.sync.pending
        # the control: a kernel this process has not compiled yet (no other test restyles to
        # tie_dye) is counted
        dr.kernel_history()
        st.style = "tie_dye"
        vp.update(bpy.context.evaluated_depsgraph_get(), st)
        finish(vp)
        assert compiled_kernels()[0], "the check could not see a new kernel"
    finally:
        dr.set_flag(dr.JitFlag.KernelHistory, False)
        vp.close()
    # a fresh export of the scene as it is now renders the image of the moved one, bit for bit
    st.style = "cel"
    fresh = start(st, frame=None)
    try:
        assert fresh.sync.moved == 0
        assert np.array_equal(fresh.session.latest()[0], images[-1])
    finally:
        fresh.close()
