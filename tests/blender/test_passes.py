"""F12's render passes: the error AOVs (variance, bias, children) and, with lines, a line mask."""
import numpy as np
import pytest
import scenes as S


def test_error_aovs_and_line_mask(tmp_path):
    S.room(32)
    out = S.styletrace(
        str(tmp_path / "lines.exr"),
        8,
        seed=2,
        pass_spp=8,
        style="cel",
        inner_samples="4",
        lines=True,
        aovs=True,
    )
    assert {"Combined", "Variance", "Bias", "Children", "LineMask"} <= set(out)
    # children averaged over the pixel's 8 samples: 4 where a sample was stylized, 0 where it met
    # sky or a line
    children = out["Children"][..., 0]
    assert children.max() == 4.0 and np.allclose(children * 2 % 1, 0)
    assert (out["Variance"] >= 0).all() and out["Variance"].mean() > 0
    mask = out["LineMask"][..., 0]
    assert mask.min() >= 0 and mask.max() <= 1
    lines = mask > 0.99
    print(f"line pixels: {lines.mean():.3f}")
    assert 0.01 < lines.mean() < 0.4
    # where a pixel is all line, the image is the line colour (black by default)
    assert out["Combined"][..., :3][lines].max() < 1e-6


def test_lifted_lines_take_their_types_colour_and_the_mask_follows(tmp_path):
    """Line mode lifted with a line dictionary from the panel: where a pixel is all line it has
    the type's own colour (red here), and the LineMask still finds the lines (the mask's renders
    override every type's colour)."""
    S.room(32)
    st = S.bpy.context.scene.styletrace
    try:
        out = S.styletrace(
            str(tmp_path / "lifted.exr"),
            8,
            seed=2,
            pass_spp=8,
            style="cel",
            inner_samples="4",
            lines=True,
            line_mode="lifted",
            line_types="shape_id color=1,0,0",
            aovs=False,
        )
        lines = out["LineMask"][..., 0] > 0.99
        print(f"lifted line pixels: {lines.mean():.3f}")
        assert 0.005 < lines.mean() < 0.4
        np.testing.assert_allclose(
            out["Combined"][..., :3][lines], [[1.0, 0.0, 0.0]] * int(lines.sum()), atol=1e-5
        )
        st.line_types = "shape_id color=1,0,0; bogus"  # refused in one line, as every bad value
        with pytest.raises(RuntimeError) as info:
            S.bpy.ops.render.render()
        message = str(info.value).strip()
        print(message)
        assert message.startswith("Error:") and "bogus" in message and "\n" not in message
    finally:
        st.lines, st.line_mode, st.line_types = False, "absorb", ""
