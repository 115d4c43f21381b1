"""The viewport in motion (issue 47): a camera move shows the image on screen carried to the new
view at once (`viewport.ViewportSession.carry`, `viewport_carry`), before the new session's draft.

The scene: a wall of random texels straight ahead and a red box in front of it. The camera pans to
the side by a distance that moves the wall's image by exactly SHIFT pixels; the box, nearer, moves
further. The image shown before the new session's draft is the old image with the wall's texels
SHIFT pixels over (to float rounding, and nearer to that shift than to a pixel either side), and
the wall uncovered behind the box is not carried: its old pixel there was the box."""
import math

import bpy
import drjit as dr
import numpy as np
import scenes as S

from styletrace.blender import camera
from styletrace.blender.viewport import Viewport

SIZE = 64
#: the wall's distance from the camera, the box's front face's, the pan in wall pixels
WALL, SHIFT = 6.0, 4


def wall_scene():
    """A wall of 16 x 16 random texels at distance WALL, a red box in front, a white world."""
    s = S.reset(SIZE)
    background = s.world.node_tree.nodes["Background"].inputs
    background["Color"].default_value, background["Strength"].default_value = (1, 1, 1, 1), 1.0
    S.plane(8, (0, 2, 1), (math.pi / 2, 0, 0), mat=S.texel_material("wall", seed=5))
    red, _ = S.material("red", Color=(0.8, 0.05, 0.05))
    S.cube(0.6, (0.3, -1.0, 1.0), mat=red)
    S.camera((0, -4, 1), (math.pi / 2, 0, 0), lens=35)
    st = s.styletrace
    st.style, st.denoise, st.spp, st.pass_spp, st.seed = "identity", "off", 4, 4, 0
    return s, st


def inner(mask: np.ndarray) -> np.ndarray:
    """Where `mask` holds in the whole 3 x 3 neighbourhood (an edge pixel's samples see both
    sides of the edge)."""
    return np.logical_and.reduce([np.roll(mask, (dy, dx), axis=(0, 1))
                                  for dy in (-1, 0, 1) for dx in (-1, 0, 1)])


def finish(s) -> np.ndarray:
    while not s.done:
        s.schedule.step()
    assert s.error is None
    return s.latest()[0]


def pan(vp, dx: float):
    """Move the scene camera by dx along x and give the viewport its new view."""
    bpy.data.objects["camera"].location.x += dx
    dg = bpy.context.evaluated_depsgraph_get()
    vp.set_sensor(camera.sensor(dg.scene_eval, 4))
    return vp.session


def test_a_camera_move_shows_the_old_image_carried_to_the_new_view():
    scene, st = wall_scene()
    vp = Viewport(start=False, clock=lambda: 0.0)
    dg = bpy.context.evaluated_depsgraph_get()
    vp.set_sensor(camera.sensor(dg.scene_eval, 4))
    vp.update(dg, st)
    first = vp.session
    old = finish(first)
    # a focal length of SIZE * 35 / 36 pixels (Blender's 36 mm sensor): dx moves the wall by SHIFT
    s = pan(vp, SHIFT * WALL / (SIZE * 35 / 36))
    s.schedule.step()  # the first step: the carried image, before the draft
    image, label = s.latest()
    assert label.startswith("reprojected") and image.shape == old.shape
    wall = np.abs(s.surfaces.depth - WALL) < 0.01
    inside = np.zeros_like(wall)
    inside[:, :SIZE - SHIFT - 1] = True
    ahead = np.roll(old, -SHIFT, axis=1)  # old[y, x + SHIFT]
    solid = inner(np.abs(first.surfaces.depth - WALL) < 0.01)
    carried_wall = wall & inside & s.kept & np.roll(solid, -SHIFT, axis=1)
    assert carried_wall.sum() > 0.6 * SIZE * SIZE
    np.testing.assert_allclose(image[carried_wall], ahead[carried_wall], atol=1e-5)
    for other in (SHIFT - 1, SHIFT + 1):  # a pixel off is far off: the wall's texels are seen
        off = np.roll(old, -other, axis=1)[carried_wall]
        assert np.abs(image[carried_wall] - off).mean() > 0.02
    # uncovered: the new view sees the wall where the old one saw the box at old[y, x + SHIFT]
    box_then = np.roll(inner(first.surfaces.depth < WALL - 1.0), -SHIFT, axis=1)
    uncovered = wall & inside & box_then
    assert uncovered.sum() >= SIZE // 8
    assert not s.kept[uncovered].any()
    # filled from the wall around it, not the naive shift's box (0.11 measured against 0.25,
    # the image's mean)
    assert np.abs(image[uncovered] - ahead[uncovered]).mean() > 0.2 * old.mean()
    s.schedule.step()  # the draft replaces it
    assert s.latest()[1].startswith("draft")
    finish(s)
    # a second move traces its carry with the kernels compiled already (every launch an
    # in-memory cache hit: test_viewport_seed.py's check)
    dr.set_flag(dr.JitFlag.KernelHistory, True)
    try:
        dr.kernel_history()
        s = pan(vp, -0.2)
        s.schedule.step()
        launches = [k for k in dr.kernel_history() if "cache_hit" in k]
        assert launches and s.latest()[1].startswith("reprojected")
        compiled = [(k["hash"], k["operation_count"], k["size"]) for k in launches
                    if not k["cache_hit"] or k["cache_disk"]]
        assert not compiled, compiled
    finally:
        dr.set_flag(dr.JitFlag.KernelHistory, False)
        vp.close()
