"""F12's data passes Depth, Normal and Vector: declared and written only where the view layer
asks for them (Cycles' switches), under Blender's names, and equal to Cycles' own passes of the
same scene (tests/blender/scenes.py's `cycles`) where a pixel sees one surface; at edges the
renderers' samples differ, so only most pixels are held to that."""
import math

import numpy as np
import scenes as S

SIZE = (64, 48)
SWITCHES = ("use_pass_z", "use_pass_normal", "use_pass_vector")


def base():
    """A wall with a box on it and a square seen from its back, under a sun; the corners of the
    view see the empty world. Keys go in linear, so a frame's neighbours are where the keys say."""
    s = S.reset(SIZE[0])
    s.render.resolution_y = SIZE[1]
    S.bpy.context.preferences.edit.keyframe_new_interpolation_type = "LINEAR"
    white, _ = S.material("white", Color=(0.8, 0.8, 0.8))
    S.plane(7, (0, 0, 0), mat=white)
    S.cube(1.0, (1.0, 0.5, 0.5), mat=white)
    # its normal points down, away from the camera above: both renderers turn it round
    S.plane(1.2, (-1.2, -0.6, 0.8), (math.pi, 0, math.radians(20)), mat=white)
    S.light("SUN", (0, 0, 10), energy=2.0)
    return s


def keyed(obj, prop, frames_values):
    for frame, value in frames_values:
        setattr(obj, prop, value)
        obj.keyframe_insert(prop, frame=frame)


def moving_camera():
    """The camera 9 above the wall slides sideways and turns 3 degrees a frame."""
    s = base()
    cam = S.camera((0, 0, 9.0), (0, 0, 0), lens=40)
    keyed(cam, "location", [(1, (-0.3, 0.2, 9.0)), (3, (0.3, -0.2, 9.0))])
    keyed(cam, "rotation_euler", [(1, (0, math.radians(-3), 0)), (3, (0, math.radians(3), 0))])
    s.frame_set(2)
    return s


def moving_objects():
    """A still camera; a sphere moves across the wall, and a collection instance (a cube) moves
    with its empty."""
    s = base()
    S.camera((0, 0, 9.0), (0, 0, 0), lens=40)
    white = S.bpy.data.materials["white"]
    ball = S.sphere(0.6, (0, 0, 1.5), mat=white)
    keyed(ball, "location", [(1, (-0.4, -0.2, 1.5)), (3, (0.4, 0.2, 1.5))])
    coll = S.bpy.data.collections.new("thing")
    s.collection.children.link(coll)
    c = S.cube(1.2, (0, 0, 0.6), mat=white)
    c.name = "crate"
    for other in list(c.users_collection):
        other.objects.unlink(c)
    coll.objects.link(c)
    s.view_layers[0].layer_collection.children["thing"].exclude = True
    e = S.bpy.data.objects.new("mover", None)
    e.instance_type, e.instance_collection = "COLLECTION", coll
    s.collection.objects.link(e)
    keyed(e, "location", [(1, (-1.5, -1.6, 0.0)), (3, (-1.0, -1.2, 0.0))])
    s.frame_set(2)
    return s


def switches(s, on: bool):
    for name in SWITCHES:
        setattr(s.view_layers[0], name, on)


def render_both(tmp_path, builder):
    s = builder()
    switches(s, True)
    st = S.styletrace(str(tmp_path / "st.exr"), 16, seed=1, denoise="off", style="identity")
    frame = s.frame_current
    S.cycles(str(tmp_path / "cy.exr"), 16)
    return st, S.read_exr(str(tmp_path / "cy.exr")), frame


def steady(values: np.ndarray, tol: float) -> np.ndarray:
    """Pixels whose 3 x 3 neighbourhood holds one value (to `tol`, every channel): one surface."""
    v = values.reshape(values.shape[0], values.shape[1], -1)
    pad = np.pad(v, ((1, 1), (1, 1), (0, 0)), mode="edge")
    h, w = v.shape[:2]
    shifted = np.stack([pad[i:i + h, j:j + w] for i in range(3) for j in range(3)])
    return (shifted.max(0) - shifted.min(0) <= tol).all(-1)


def one_surface(st, cy) -> np.ndarray:
    """Pixels where both renderers see one flat surface: depth and normal steady around them."""
    return (steady(st["Depth"], 1e-3) & steady(cy["Depth"], 1e-3) & steady(st["Normal"], 1e-4)
            & steady(cy["Normal"], 1e-4))


def compare(st, cy, name, tol):
    a, b = st[name], cy[name]
    one = one_surface(st, cy)
    err = np.abs(a - b).max(-1)
    share = np.mean(err <= tol)
    print(f"{name}: {one.mean():.2f} of the pixels see one surface, largest error there "
          f"{err[one].max():.2e}; {share:.3f} of all pixels within {tol}")
    return one, err, share


def test_passes_appear_only_when_the_view_layer_asks(tmp_path):
    s = base()
    S.camera((0, 0, 9.0), (0, 0, 0), lens=40)
    switches(s, False)
    off = S.styletrace(str(tmp_path / "off.exr"), 2, denoise="off")
    assert not {"Depth", "Normal", "Vector"} & set(off)
    s.view_layers[0].use_pass_normal = True
    one = S.styletrace(str(tmp_path / "one.exr"), 2, denoise="off")
    assert "Normal" in one and not {"Depth", "Vector"} & set(one)
    switches(s, True)
    on = S.styletrace(str(tmp_path / "on.exr"), 2, denoise="off")
    assert on["Depth"].shape == (SIZE[1], SIZE[0], 1)
    assert on["Normal"].shape[-1] == 3 and on["Vector"].shape[-1] == 4
    # the image does not change with the passes (same seed)
    assert np.array_equal(on["Combined"], off["Combined"])
    from styletrace.blender import panels
    assert [name for _, name in panels.pass_rows(s.view_layers[0])][:3] == list(SWITCHES)


def test_a_moving_camera_matches_cycles(tmp_path):
    st, cy, frame = render_both(tmp_path, moving_camera)
    assert S.bpy.context.scene.frame_current == frame == 2  # put back after the frames around
    background = cy["Depth"][..., 0] >= 1e9
    assert 0.01 < background.mean() < 0.3
    assert np.mean((st["Depth"][..., 0] >= 1e9) == background) > 0.97
    assert (st["Depth"][..., 0][background & steady(cy["Depth"], 0)] == 1e10).all()
    one, err, share = compare(st, cy, "Depth", 1e-3)
    assert one.mean() > 0.5 and err[one].max() < 1e-3 and share > 0.95
    one, err, share = compare(st, cy, "Normal", 1e-3)
    assert one.mean() > 0.5 and err[one].max() < 1e-3 and share > 0.95
    # the square seen from its back (at height 0.8: depth 8.2): Cycles turns its normal towards
    # the camera, and so does styletrace
    back = one & (np.abs(cy["Depth"][..., 0] - 8.2) < 1e-3)
    assert back.sum() > 10
    np.testing.assert_allclose(st["Normal"][back], np.tile([0, 0, 1.0], (back.sum(), 1)),
                               atol=1e-5)
    one, err, share = compare(st, cy, "Vector", 0.02)
    assert one.mean() > 0.5 and err[one].max() < 0.02 and share > 0.9
    assert np.abs(cy["Vector"]).max() > 2.0  # the camera's motion shows
    assert np.abs(st["Vector"][background & steady(cy["Depth"], 0)]).max() == 0.0


def test_moving_objects_match_cycles(tmp_path):
    st, cy, _ = render_both(tmp_path, moving_objects)
    moving = np.abs(cy["Vector"]).max(-1) > 0.5
    print(f"{moving.mean():.3f} of the pixels move")
    assert moving.mean() > 0.03
    _, err, share = compare(st, cy, "Vector", 0.02)
    assert share > 0.9
    # inside a moving object (no edge around the pixel): the sphere, and the instanced cube,
    # whose top is 1.2 high (depth 7.8)
    inside = moving & steady(moving.astype(float), 0)
    crate = inside & (np.abs(cy["Depth"][..., 0] - 7.8) < 1e-3)
    print(f"{inside.sum()} pixels inside moving objects, {crate.sum()} on the instance; largest "
          f"error {err[inside].max():.2e}")
    assert inside.sum() > 60 and crate.sum() > 5 and err[inside].max() < 0.02
    still = steady(cy["Vector"], 0) & ~moving
    assert np.abs(st["Vector"][still]).max() == 0.0


def test_render_animation_writes_each_frames_motion(tmp_path):
    """Render Animation of frames 2 and 3: frame 2's passes are F12's, and frame 3, the camera's
    last key, moves towards frame 2 but not towards frame 4 (the keys hold after the last)."""
    s = moving_camera()
    switches(s, True)
    still = S.styletrace(str(tmp_path / "f12.exr"), 4, seed=1, denoise="off", style="identity")
    s.frame_start, s.frame_end = 2, 3
    s.render.filepath = str(tmp_path / "anim_")
    S.bpy.ops.render.render(animation=True)
    assert s.frame_current == 2
    two, three = (S.read_exr(str(tmp_path / f"anim_{f:04d}.exr")) for f in (2, 3))
    for name in ("Depth", "Normal", "Vector"):
        assert np.array_equal(two[name], still[name]), name
    seen = three["Depth"][..., 0] < 1e9
    assert np.abs(three["Vector"][seen][:, :2]).min() > 0.5
    assert np.abs(three["Vector"][..., 2:]).max() == 0.0


def test_the_compositors_vector_blur_reads_the_passes_as_cycles(tmp_path):
    """A red ball moving sideways over a wall, composited with Blender's Vector Blur node (Image,
    Vector as Speed, Depth as Z): styletrace's composite blurs the ball as Cycles' does (the mean
    of the rows through it, to within the renders' noise), and leaves it sharp without the node."""
    s = S.reset(SIZE[0])
    s.render.resolution_y = SIZE[1]
    white, _ = S.material("white", Color=(0.8, 0.8, 0.8))
    red, _ = S.material("red", Color=(0.8, 0.1, 0.1))
    S.plane(7, (0, 0, 0), mat=white)
    ball = S.sphere(0.8, (0, 0, 1.5), mat=red)
    keyed(ball, "location", [(1, (-0.8, 0, 1.5)), (3, (0.8, 0, 1.5))])
    S.light("SUN", (0, 0, 10), energy=2.0)
    S.camera((0, 0, 9.0), (0, 0, 0), lens=40)
    s.frame_set(2)
    s.view_layers[0].use_pass_z = s.view_layers[0].use_pass_vector = True
    tree = S.bpy.data.node_groups.new("comp", "CompositorNodeTree")
    s.compositing_node_group = tree
    tree.interface.new_socket("Image", in_out="OUTPUT", socket_type="NodeSocketColor")
    layers, blur = tree.nodes.new("CompositorNodeRLayers"), tree.nodes.new("CompositorNodeVecBlur")
    layers.scene = s
    for out, into in (("Image", "Image"), ("Vector", "Speed"), ("Depth", "Z")):
        tree.links.new(layers.outputs[out], blur.inputs[into])
    tree.links.new(blur.outputs[0], tree.nodes.new("NodeGroupOutput").inputs[0])
    s.render.image_settings.media_type = "IMAGE"
    s.render.image_settings.file_format = "OPEN_EXR"

    def composite(name, engine, compositing=True):
        s.render.use_compositing = compositing
        path = str(tmp_path / f"{name}.exr")
        if engine == "CYCLES":
            S.cycles(path, 16)
        else:
            S.styletrace(path, 16, seed=1, denoise="off", style="identity")
        return S.read_exr(path)["Combined"][..., 1]  # green: the wall's, not the red ball's

    mine, theirs = composite("st", "STYLETRACE"), composite("cy", "CYCLES")
    sharp = composite("sharp", "STYLETRACE", compositing=False)
    rows = slice(SIZE[1] // 2 - 3, SIZE[1] // 2 + 4)
    a, b, c = (img[rows].mean(0) for img in (mine, theirs, sharp))
    print("styletrace", np.round(a[12:52], 2), "\ncycles    ", np.round(b[12:52], 2),
          "\nunblurred ", np.round(c[12:52], 2))
    assert np.abs(a - c).max() > 0.1  # the node blurred the ball
    assert np.abs(a - b).max() < 0.05
