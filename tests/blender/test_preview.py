"""Material previews with the styletrace engine (`blender.preview`): Blender renders its preview
scene through the engine (`is_preview`) with the material's own style at the preview's budget. A
cel material's preview ball has the cel's few levels where an unstyled one has a continuum, and a
preview leaves the user's last render (the restyle buffer, `engine.LAST`) as it was."""
import time

import bpy
import numpy as np
import scenes as S

from styletrace.blender import engine, preview, restyle

LEVELS = (0.2, 0.9)
#: seconds a preview may take on a loaded 2-core machine (a first one compiles its kernels)
PATIENCE = 300


def srgb_to_linear(v):
    v = np.asarray(v, np.float64)
    return np.where(v <= 0.04045, v / 12.92, ((v + 0.055) / 1.055) ** 2.4)


def preview_of(mat) -> np.ndarray:
    """Generate `mat`'s preview (Blender's preview job, which calls the engine in its own thread)
    and return its pixels (H x W x 4, 8-bit display values over 255, top row first)."""
    before = dict(engine.PREVIEW)
    with bpy.context.temp_override(id=mat):
        bpy.ops.ed.lib_id_generate_preview()
    p = mat.preview
    deadline = time.monotonic() + PATIENCE
    last = None
    while time.monotonic() < deadline:
        time.sleep(0.5)  # lets the job's thread take Python's lock
        px = np.array(p.image_pixels_float[:], np.float64)
        # done: the engine ran, and the pixels Blender copied out of its result stopped changing
        if engine.PREVIEW != before and px.max() > 0 and last is not None and (px == last).all():
            w, h = p.image_size
            return px.reshape(h, w, 4)[::-1]
        last = px
    raise AssertionError(f"no preview of {mat.name} within {PATIENCE} s")


def on_lattice(img, spp):
    """Per pixel: whether the 8-bit grey value could come from a brightness on the cel lattice
    L0 + k (L1 - L0) / spp (each of the spp samples at one of the two levels): the interval of
    linear values that round to the pixel's byte holds a lattice point. Also the chance that a
    brightness off the lattice lands on it: the interval's width over the lattice's spacing."""
    byte = np.round(img[..., :3].mean(axis=-1) * 255)
    lo, hi = srgb_to_linear((byte - 0.5) / 255), srgb_to_linear((byte + 0.5) / 255)
    step = (LEVELS[1] - LEVELS[0]) / spp
    k_lo, k_hi = np.ceil((lo - LEVELS[0]) / step), np.floor((hi - LEVELS[0]) / step)
    return (k_lo <= k_hi) & (k_hi >= 0) & (k_lo <= spp), np.minimum((hi - lo) / step, 1.0)


def test_preview_shows_the_materials_style_and_keeps_the_last_render(tmp_path):
    s = S.room(24)
    s.render.engine = "STYLETRACE"
    s.view_settings.view_transform = "Standard"  # the preview uses the scene's: sRGB bytes
    S.styletrace(str(tmp_path / "recorded.exr"), 8, seed=9, pass_spp=8, style="cel",
                 record_buffer=True, inner_samples="4")
    recorded, last = restyle.buffer(), dict(engine.LAST)
    bpy.data.images["Render Result"].save_render(str(tmp_path / "before.exr"))
    assert recorded is not None

    mat, _ = S.material("ball", Color=(0.8, 0.8, 0.8))
    plain = preview_of(mat)
    st = mat.styletrace
    st.use_style, st.style = True, "cel"
    st.params.cel__levels = ",".join(map(str, LEVELS))
    st.inner_samples = "8"
    cel = preview_of(mat)
    print(f"preview: {plain.shape[1]}x{plain.shape[0]}, {engine.PREVIEW}")
    assert engine.PREVIEW["spp_done"] == engine.PREVIEW["spp_total"] == preview.SAMPLES

    h, w = cel.shape[:2]
    y, x = np.mgrid[:h, :w]
    # the preview ball fills the image's middle: a disc of a quarter of the size is all ball
    ball = (x + 0.5 - w / 2) ** 2 + (y + 0.5 - h / 2) ** 2 < (w / 4) ** 2
    q_cel, _ = on_lattice(cel, engine.PREVIEW["spp_total"])
    q_plain, chance = on_lattice(plain, engine.PREVIEW["spp_total"])
    p, n = chance[ball].mean(), ball.sum()
    print(f"on the cel lattice: cel {q_cel[ball].mean():.3f}, plain {q_plain[ball].mean():.3f} "
          f"(chance {p:.3f}, {n} pixels)")
    assert q_cel[ball].all()
    assert q_plain[ball].mean() < p + 4 * np.sqrt(p * (1 - p) / n)  # no more than by chance
    assert np.abs(cel - plain)[ball].mean() > 0.01  # and the images differ

    # the user's last render is untouched: the recorded buffer, LAST, the Render Result
    assert restyle.buffer() is recorded and engine.LAST == last
    bpy.data.images["Render Result"].save_render(str(tmp_path / "after.exr"))
    files = [str(tmp_path / f"{k}.exr") for k in ("before", "after")]
    before, after = (S.read_exr(f)["Combined"] for f in files)
    np.testing.assert_array_equal(before, after)
