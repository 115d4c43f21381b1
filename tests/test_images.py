"""Writing images: EXR linear, PNG sRGB, and a render is never lost to a failed write."""
import os

import mitsuba as mi
import numpy as np

import styletrace
from styletrace.images import save_safely

styletrace.init()


def read(path):
    bmp = mi.Bitmap(str(path))
    scale = 255.0 if bmp.component_format() == mi.Struct.Type.UInt8 else 1.0
    return np.array(bmp, dtype=np.float64) / scale


def test_a_failed_write_keeps_the_render(tmp_path, capsys):
    """If writing fails after rendering (e.g. the folder vanished), the image goes to a temporary EXR."""
    img = np.full((4, 6, 3), 0.25, dtype=np.float32)
    out = save_safely(img, str(tmp_path / "gone" / "x.png"))
    assert out != str(tmp_path / "gone" / "x.png") and out.endswith(".exr")
    np.testing.assert_array_equal(read(out), img)
    assert "saved the render to" in capsys.readouterr().err
    os.remove(out)

