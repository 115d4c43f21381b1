"""Render Animation with the styletrace engine (`blender.animation`): Blender's frame range, output
paths and file formats; each written frame equals an F12 of that frame (frame_set, then render) and
shows the frame's state; every frame gets its own noise (the seed depends on the frame); Esc during
a frame ends the sequence, the frames before it written and the cancelled frame's finished passes
kept in the Render Result (Blender writes no cancelled frame)."""
import math
import os

import bpy
import numpy as np
import pytest
import scenes as S
from bpy_extras.object_utils import world_to_camera_view

from styletrace.blender import animation, engine

FRAMES = (3, 4, 5)  # not from 1: the range is Blender's
SIZE, SPP, PASS_SPP, SEED = 40, 16, 4, 5


def moving_scene(still: bool = False):
    """The room with a small blue emitting cube keyframed across it, frames 3 to 5 (keyframed in
    one place if `still`)."""
    s = S.room(SIZE)
    blue, _ = S.material("blue", "ShaderNodeEmission", Color=(0.0, 0.0, 1.0), Strength=20.0)
    cube = S.cube(0.5, (0, -1.5, 1.0), mat=blue)
    for f, x in ((FRAMES[0], -1.2), (FRAMES[-1], -1.2 if still else 1.2)):
        cube.location.x = x
        cube.keyframe_insert("location", frame=f)
    s.frame_start, s.frame_end = FRAMES[0], FRAMES[-1]
    s.render.engine = "STYLETRACE"
    st = s.styletrace
    st.spp, st.pass_spp, st.seed, st.style, st.denoise = SPP, PASS_SPP, SEED, "identity", "off"
    st.inner_samples = "1"  # explicit counts: an F12 with fewer camera samples keeps one child
    return s, cube


def image_format(s, fmt):
    im = s.render.image_settings
    if fmt == "OPEN_EXR_MULTILAYER":
        return "exr"  # as scenes.reset set it
    im.media_type = "IMAGE"
    im.file_format = fmt
    return {"PNG": "png", "OPEN_EXR": "exr"}[fmt]


def read(path):
    """Every pass of a file Blender wrote (a PNG's pixels as 'Combined', 8-bit values)."""
    if path.endswith(".png"):
        import mitsuba as mi
        return {"Combined": np.array(mi.Bitmap(path))}
    return S.read_exr(path)


def f12_of(s, frame, path, ext):
    """F12 of `frame`: Blender sets the frame, then renders and writes the still to `path`.`ext`."""
    s.frame_set(frame)
    s.render.filepath = path
    bpy.ops.render.render(write_still=True)
    return read(f"{path}.{ext}")


def render_animation(s, tmp_path, ext):
    folder = tmp_path / "anim"
    s.render.filepath = str(folder / "frame_####")
    bpy.ops.render.render(animation=True)
    return folder


@pytest.mark.parametrize("fmt", ["PNG", "OPEN_EXR"])
def test_each_written_frame_is_the_f12_of_its_frame(fmt, tmp_path):
    s, cube = moving_scene()
    ext = image_format(s, fmt)
    folder = render_animation(s, tmp_path, ext)
    # Blender's names: the #### of the output path is the frame, the extension the format's
    assert sorted(os.listdir(folder)) == [f"frame_{f:04d}.{ext}" for f in FRAMES]
    written = {}
    for f in FRAMES:
        s.render.filepath = str(folder / "frame_####")
        written[f] = read(s.render.frame_path(frame=f))["Combined"]
    centres = []
    for f in FRAMES:
        still = f12_of(s, f, str(tmp_path / f"still_{f}"), ext)["Combined"]
        if ext == "png":
            np.testing.assert_array_equal(written[f], still)
        else:
            np.testing.assert_allclose(written[f], still, rtol=1e-6, atol=1e-7)
        # the frame's state: the blue cube is where Blender's camera projects it at this frame
        cam = world_to_camera_view(s, s.camera, cube.matrix_world.translation)
        img = written[f].astype(np.float64)
        b = img[..., 2]
        mask = (b >= 0.9 * b.max()) & (img[..., 0] + img[..., 1] < 0.2 * b)
        x = (np.nonzero(mask)[1] + 0.5).mean()
        centres.append((x, cam.x * SIZE))
        assert abs(x - cam.x * SIZE) < 1.0, (f, x, cam.x * SIZE)  # within a pixel
    print(f"{fmt}: cube centre x (image, projected) per frame: {centres}")
    assert centres[0][0] < centres[1][0] < centres[2][0]  # it moved


def test_every_frame_has_its_own_noise(tmp_path):
    """A still scene animated over frames 3 to 5: the frames Blender wrote differ by independent
    noise, so sum (a - b)^2 over the pixels matches the sum of both frames' Variance passes (ratio
    1 within four standard errors of the ratio estimator). With one seed for every frame the frames
    would be equal (ratio 0). Independent samples: with the Owen-scrambled sequence the Variance
    pass is an upper bound of the mean's variance, not its value."""
    s, _ = moving_scene(still=True)
    s.styletrace.sampler = "independent"
    folder = render_animation(s, tmp_path, image_format(s, "OPEN_EXR_MULTILAYER"))
    s.render.filepath = str(folder / "frame_####")
    a = read(s.render.frame_path(frame=FRAMES[0]))
    for f in FRAMES[1:]:
        b = read(s.render.frame_path(frame=f))
        x = ((a["Combined"][..., :3] - b["Combined"][..., :3]).astype(np.float64) ** 2).sum(-1)
        y = (a["Variance"] + b["Variance"]).astype(np.float64).sum(-1)
        x, y = x.ravel(), y.ravel()
        ratio = x.sum() / y.sum()
        se = np.sqrt(np.var(x - ratio * y) / x.size) / y.mean()
        print(f"frames {FRAMES[0]} and {f}: sum of squared differences / sum of variances = "
              f"{ratio:.3f} (standard error {se:.3f})")
        assert abs(ratio - 1) < 4 * se


def test_frame_seed():
    """Frame 1 renders with the Seed itself (F12 of a scene never animated is unchanged), frame f
    with Seed + f - 1, modulo 2^32 below frame 1."""
    assert [animation.frame_seed(7, f) for f in (1, 2, 5)] == [7, 8, 11]
    assert animation.frame_seed(0, 0) == 2 ** 32 - 1


def test_esc_during_a_frame_ends_the_sequence(tmp_path, monkeypatch):
    s, _ = moving_scene()
    ext = image_format(s, "OPEN_EXR_MULTILAYER")
    rendered, polls = [], []
    real = engine.StyletraceEngine._render

    def render(self, depsgraph):
        rendered.append(depsgraph.scene.frame_current)
        real(self, depsgraph)

    def test_break(self):  # Esc pressed while frame 4's second pass is shown
        if bpy.context.scene.frame_current == FRAMES[1]:
            polls.append(1)
        return len(polls) >= 2

    monkeypatch.setattr(engine.StyletraceEngine, "_render", render)
    monkeypatch.setattr(engine.StyletraceEngine, "stop_requested", test_break)
    done = PASS_SPP + 2 * PASS_SPP  # two passes, F12's doubling (`f12.job`)
    with pytest.raises(RuntimeError, match=f"cancelled during frame {FRAMES[1]} after {done} of "
                                           f"{SPP} spp: Render Animation stops here"):
        render_animation(s, tmp_path, ext)
    assert rendered == list(FRAMES[:2])  # frame 5 was not rendered
    folder = tmp_path / "anim"
    assert sorted(os.listdir(folder)) == [f"frame_{FRAMES[0]:04d}.{ext}"]  # nor frame 4 written
    first = read(str(folder / f"frame_{FRAMES[0]:04d}.{ext}"))
    kept = str(tmp_path / "kept.exr")
    bpy.data.images["Render Result"].save_render(kept)  # frame 4's finished passes
    kept = read(kept)
    monkeypatch.undo()
    full = f12_of(s, FRAMES[0], str(tmp_path / "full"), ext)
    np.testing.assert_allclose(first["Combined"], full["Combined"], rtol=1e-6, atol=1e-7)
    s.styletrace.spp = done
    partial = f12_of(s, FRAMES[1], str(tmp_path / "partial"), ext)
    np.testing.assert_allclose(kept["Combined"], partial["Combined"], rtol=1e-6, atol=1e-7)
    assert not math.isclose(float(kept["Combined"].mean()), float(full["Combined"].mean()))
