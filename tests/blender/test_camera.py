"""Cameras against Cycles: shift, sensor fit on a non-square image, orthographic, depth of field,
the resolution percentage. The room (test_cycles) seen through each camera variant; the image
mean within 2% and the 8x8 blocks' z-test as in test_cycles, with Cycles references cached the
same way."""

import bpy
import numpy as np
import pytest
import scenes as S
from test_cycles import Z

VARIANTS = {
    "shift": dict(shift_x=0.15, shift_y=-0.1),
    "vertical_fit": dict(sensor_fit="VERTICAL", sensor_height=30.0),
    "ortho": dict(type="ORTHO", ortho_scale=5.0),
    "ortho_shift": dict(type="ORTHO", ortho_scale=5.0, shift_x=0.1, shift_y=0.05),
    "dof": dict(dof=dict(use_dof=True, focus_distance=3.0, aperture_fstop=0.5)),
}


def build(variant):
    S.room(64)
    s = bpy.context.scene
    # 48 x 32 pixels
    s.render.resolution_x, s.render.resolution_y, s.render.resolution_percentage = 96, 64, 50
    cam = s.camera.data
    for key, value in VARIANTS[variant].items():
        if key == "dof":
            for k, v in value.items():
                setattr(cam.dof, k, v)
        else:
            setattr(cam, key, value)


@pytest.mark.parametrize("variant", sorted(VARIANTS))
def test_camera_matches_cycles(variant, tmp_path):
    ref, ref_var = S.cycles_reference(f"camera_{variant}", 512, lambda: build(variant))
    build(variant)
    out = S.styletrace(
        str(tmp_path / "st.exr"), 128, seed=4, pass_spp=128, style="identity", aovs=True
    )
    img = out["Combined"][..., :3]
    assert img.shape == ref.shape == (32, 48, 3)
    z = S.block_z(img, out["Variance"], ref, ref_var)
    ratio = img.mean(axis=(0, 1)) / ref.mean(axis=(0, 1))
    print(
        f"{variant}: ratio {ratio}, blocks passing {np.mean(np.abs(z) < Z):.3f}, max |z| "
        f"{np.abs(z).max():.2f}"
    )
    assert np.all(np.abs(ratio - 1) < 0.02) and np.mean(np.abs(z) < Z) >= 0.99
