"""Temporal reuse in Render Animation (`blender.animation.frame_history`, denoise/temporal.py).

The room, 40 x 40, cel at Samples 16, Denoise auto (the expectation denoiser), frames 1 to 5:
- a still shot with Temporal reuse on: frame 1 is the F12 of frame 1 (nothing to reuse), the later
  frames are not their F12s, and the last frame changes less from the one before than with reuse
  off (display-space pixels changing by more than 0.1);
- with Temporal reuse off, every written frame is the F12 of its frame (today's frames);
- a cube that moves every frame: the view changes, so each frame starts again and is its F12;
- a second Render Animation of the same still shot starts again at its first frame.
"""
import os

import bpy
import numpy as np
import scenes as S

from styletrace.measures import srgb

FRAMES = (1, 2, 3, 4, 5)
SIZE = 40


def shot(moving: bool = False, reuse: bool = True):
    s = S.room(SIZE)
    red, _ = S.material("red", "ShaderNodeBsdfDiffuse", Color=(0.8, 0.1, 0.1))
    cube = S.cube(0.6, (-0.8, 0.0, 0.3), mat=red)
    if moving:
        for f, x in ((FRAMES[0], -0.8), (FRAMES[-1], 0.8)):
            cube.location.x = x
            cube.keyframe_insert("location", frame=f)
    s.frame_start, s.frame_end = FRAMES[0], FRAMES[-1]
    s.render.engine = "STYLETRACE"
    st = s.styletrace
    st.style, st.samples, st.denoise, st.seed = "cel", 16, "auto", 3
    st.temporal_reuse = reuse
    return s


def animation(s, folder):
    s.render.filepath = str(folder / "frame_####")
    bpy.ops.render.render(animation=True)
    return [S.read_exr(s.render.frame_path(frame=f))["Combined"][..., :3] for f in FRAMES]


def f12(s, frame, path):
    s.frame_set(frame)
    s.render.filepath = path
    bpy.ops.render.render(write_still=True)
    return S.read_exr(path + ".exr")["Combined"][..., :3]


def changed(a, b):
    return float(np.mean(np.abs(srgb(a) - srgb(b)).max(axis=-1) > 0.1))


def test_a_still_shots_frames_settle_with_reuse_and_are_their_f12s_without(tmp_path):
    s = shot(reuse=True)
    reused = animation(s, tmp_path / "on")
    first = f12(s, FRAMES[0], str(tmp_path / "f12_1"))
    np.testing.assert_allclose(reused[0], first, rtol=1e-6, atol=1e-7)
    last = f12(s, FRAMES[-1], str(tmp_path / "f12_5"))
    assert not np.allclose(reused[-1], last, rtol=1e-4, atol=1e-4)
    s.styletrace.temporal_reuse = False
    plain = animation(s, tmp_path / "off")
    for f, img in zip(FRAMES, plain):
        np.testing.assert_allclose(img, f12(s, f, str(tmp_path / f"plain_{f}")), rtol=1e-6,
                                   atol=1e-7)
    before, after = changed(plain[-2], plain[-1]), changed(reused[-2], reused[-1])
    print(f"pixels changed from frame 4 to 5: {before:.2%} without reuse, {after:.2%} with")
    assert after < 0.5 * before


def test_a_moving_cube_starts_the_history_again_every_frame(tmp_path):
    s = shot(moving=True, reuse=True)
    written = animation(s, tmp_path / "anim")
    for f, img in zip(FRAMES, written):
        np.testing.assert_allclose(img, f12(s, f, str(tmp_path / f"f12_{f}")), rtol=1e-6,
                                   atol=1e-7)


def test_a_second_animation_starts_again(tmp_path):
    s = shot(reuse=True)
    one = animation(s, tmp_path / "one")
    two = animation(s, tmp_path / "two")
    for a, b in zip(one, two):
        np.testing.assert_allclose(a, b, rtol=1e-6, atol=1e-7)
    assert os.path.exists(tmp_path / "two")
