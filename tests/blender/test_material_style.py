"""A per-material style: the room's red wall gets cel shading through its material's styletrace
panel (a `styled` BSDF); everything else stays physically based. The wall's pixels come from
Cycles' material-index pass, so the mask does not depend on styletrace's exporter."""
import os

import bpy
import numpy as np
import scenes as S

LEVELS = (0.2, 0.9)
SPP = 16


def red_wall_mask(tmp_path):
    """Pixels wholly on the red wall, and pixels wholly off it (each eroded by one pixel)."""
    s = bpy.context.scene
    bpy.data.materials["red"].pass_index = 1
    s.view_layers[0].use_pass_material_index = True
    S.cycles(os.path.join(tmp_path, "index.exr"), 4)
    index = S.read_exr(os.path.join(tmp_path, "index.exr"))["Material Index"][..., 0]
    on = np.isclose(index, 1.0)

    def erode(m):
        out = m.copy()
        out[1:] &= m[:-1]
        out[:-1] &= m[1:]
        out[:, 1:] &= m[:, :-1]
        out[:, :-1] &= m[:, 1:]
        return out

    return erode(on), erode(~on)


def test_cel_on_one_material_only(tmp_path):
    S.room(48)
    inside, outside = red_wall_mask(tmp_path)
    assert inside.sum() > 100 and outside.sum() > 500
    identity = S.styletrace(
        os.path.join(tmp_path, "a.exr"), SPP, seed=3, pass_spp=SPP, style="identity", aovs=False
    )["Combined"][..., :3]
    st = bpy.data.materials["red"].styletrace
    st.use_style, st.style = True, "cel"
    st.params.cel__levels = ",".join(map(str, LEVELS))
    st.inner_samples = "8"
    cel = S.styletrace(os.path.join(tmp_path, "b.exr"), SPP, seed=3, pass_spp=SPP, style="identity",
                       aovs=False)["Combined"][..., :3]

    def quantised(img):
        """cel: each of a pixel's SPP camera samples has one of the levels as brightness, so the
        pixel's brightness is level0 + k (level1 - level0) / SPP for an integer k."""
        k = (img.mean(axis=-1) - LEVELS[0]) / ((LEVELS[1] - LEVELS[0]) / SPP)
        return np.abs(k - np.round(k)) < 0.02

    q = quantised(cel)
    print(f"quantised: inside {q[inside].mean():.3f}, outside {q[outside].mean():.3f}")
    assert q[inside].mean() > 0.98
    # 4% of the lattice's width: about 4% of unstyled pixels land on it by chance
    assert q[outside].mean() < 0.2
    # the physically based wall is not: the style did it
    assert quantised(identity)[inside].mean() < 0.2
    # off the wall, the image is the physically based one (first_hit: the wall's light reaches
    # others unstyled)
    diff = np.abs(cel - identity)[outside].mean() / identity[outside].mean()
    print(f"outside: relative mean difference {diff:.4f}")
    assert diff < 0.01
