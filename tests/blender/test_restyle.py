"""Restyle inside Blender: with Record buffer on, F12 keeps the look-development buffer, and
changing a style parameter restyles it (the property's update callback) into the image
'styletrace restyle' without a render (milliseconds: BENCHMARKS.md); the image equals a fresh F12
render with the new value and the same seed, up to float rounding."""
import time

import bpy
import numpy as np
import pytest
import scenes as S

from styletrace.blender import engine, restyle


def pixels(image):
    w, h = image.size
    px = np.empty(w * h * 4, np.float32)
    image.pixels.foreach_get(px)
    return px.reshape(h, w, 4)[::-1, :, :3]


def test_parameter_change_restyles_the_buffer(tmp_path):
    S.room(32)
    st = bpy.context.scene.styletrace
    S.styletrace(
        str(tmp_path / "recorded.exr"),
        8,
        seed=9,
        pass_spp=8,
        style="cel",
        record_buffer=True,
        inner_samples="4",
    )
    assert restyle.buffer() is not None
    rendered = dict(engine.LAST)
    t0 = time.perf_counter()
    st.params.cel__levels = "0.1,0.5"  # the update callback restyles
    seconds = time.perf_counter() - t0
    print(
        f"restyle took {restyle.last_seconds() * 1000:.1f} ms ({seconds * 1000:.1f} ms with the "
        f"callback)"
    )
    assert engine.LAST == rendered  # no render: the buffer restyled
    st.params.cel__levels = "0.15,0.6"  # again, with the kernel compiled
    print(f"second restyle took {restyle.last_seconds() * 1000:.1f} ms")
    st.params.cel__levels = "0.1,0.5"
    restyled = pixels(bpy.data.images[restyle.IMAGE])
    fresh = S.styletrace(
        str(tmp_path / "fresh.exr"),
        8,
        seed=9,
        pass_spp=8,
        style="cel",
        record_buffer=False,
        aovs=False,
    )["Combined"][..., :3]
    np.testing.assert_allclose(restyled, fresh, rtol=1e-4, atol=1e-5)
    # a refused value: the operator's one-line report; the image stays
    st.record_buffer = True
    S.styletrace(
        str(tmp_path / "recorded2.exr"), 8, seed=9, pass_spp=8, style="cel", record_buffer=True
    )
    st.params.cel__levels = "0.1,x"  # the callback prints the refusal and keeps the previous image
    with pytest.raises(RuntimeError, match=r"^Error: bad value '0.1,x' for parameter 'levels'"):
        bpy.ops.styletrace.restyle()
