"""Temporal reuse in Render Animation (`blender.animation.frame_history`, denoise/temporal.py).

The room, 40 x 40, cel at Samples 16, Denoise auto (the expectation denoiser), frames 1 to 5:
- a still shot with Temporal reuse on: frame 1 is the F12 of frame 1 (nothing to reuse), the later
  frames are not their F12s, and the last frame changes less from the one before than with reuse
  off (display-space pixels changing by more than 0.1);
- with Temporal reuse off, every written frame is the F12 of its frame (today's frames);
- a cube that moves every frame, in front of the plain walls and of a back wall of random grey
  texels: the wall it uncovers carries no trace of it (the history is carried along the Vector
  pass and refused where the depth differs);
- a second Render Animation of the same still shot starts again at its first frame.
"""
import os

import bpy
import numpy as np
import pytest
import scenes as S

from styletrace.measures import srgb

FRAMES = (1, 2, 3, 4, 5)
SIZE = 40


def texel_wall():
    """The room's back wall covered with 16 x 16 random grey texels (no blueness of its own)."""
    mat = S.texel_material("texels", seed=7, grey=True)
    wall = next(o for o in bpy.data.objects
                if o.type == "MESH" and tuple(round(v, 3) for v in o.location) == (0, 2, 2))
    wall.data.materials.clear()
    wall.data.materials.append(mat)


def shot(moving: bool = False, reuse: bool = True, textured: bool = False):
    s = S.room(SIZE)
    if textured:
        texel_wall()
    blue, _ = S.material("blue", "ShaderNodeBsdfDiffuse", Color=(0.05, 0.1, 0.9))
    cube = S.cube(0.6, (-0.8, 0.0, 0.3), mat=blue)
    if moving:
        for f, x in ((FRAMES[0], -1.6), (FRAMES[-1], 1.6)):
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


def blueness(img):
    """How much bluer than grey: the room's walls are white, red and green, the cube blue."""
    return img[..., 2] - 0.5 * (img[..., 0] + img[..., 1])


@pytest.mark.parametrize("textured", [False, True], ids=["plain", "texels"])
def test_a_moving_cube_leaves_no_trace_where_it_was(tmp_path, textured):
    """The blue cube moves across the room: the wall it uncovers in frame k (blue in frame k - 1's
    F12, not in frame k's) is carried no history of the cube (its depth differs), so the
    reused frame is no bluer there than frame k's own F12 (within a tenth of the cube's
    blueness), while on the cube itself the history is carried along; the same in front of a
    wall of random grey texels."""
    s = shot(moving=True, reuse=True, textured=textured)
    written = animation(s, tmp_path / "anim")
    np.testing.assert_allclose(written[0], f12(s, FRAMES[0], str(tmp_path / "f12_1")),
                               rtol=1e-6, atol=1e-7)
    alone = [f12(s, f, str(tmp_path / f"f12_{f}")) for f in FRAMES]
    for k in range(1, len(FRAMES)):
        was = blueness(alone[k - 1]) > 0.5 * blueness(alone[k - 1]).max()
        now = blueness(alone[k]) > 0.5 * blueness(alone[k]).max()
        uncovered = was & ~now
        assert uncovered.sum() >= 10, k  # the cube moved far enough to uncover some wall
        ghost = blueness(written[k])[uncovered].mean() - blueness(alone[k])[uncovered].mean()
        print(f"frame {FRAMES[k]}: the uncovered wall is bluer than its F12 by {ghost:.4f}, "
              f"{ghost / blueness(alone[k - 1])[was].mean():.1%} of the cube's blueness")
        assert ghost < 0.1 * blueness(alone[k - 1])[was].mean(), (k, ghost)
    assert not np.allclose(written[-1], alone[-1], rtol=1e-4, atol=1e-4)  # history was used


def test_a_second_animation_starts_again(tmp_path):
    s = shot(reuse=True)
    one = animation(s, tmp_path / "one")
    two = animation(s, tmp_path / "two")
    for a, b in zip(one, two):
        np.testing.assert_allclose(a, b, rtol=1e-6, atol=1e-7)
    assert os.path.exists(tmp_path / "two")
