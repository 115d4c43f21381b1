"""Scenes with textures and an EXR environment map render from the command line in bounded time.

Before commit 76e347f the loader ran Dr.Jit on one thread and Mitsuba's OpenEXR reader deadlocked on
that thread pool: `styletrace render` on any scene with an EXR texture or environment map never
returned. Each render here runs in its own process (a deadlock must not take the test session with
it) and must finish, successfully and with a finite image, within LIMIT seconds; the renders
themselves take a few seconds.
"""
import subprocess
import sys

import numpy as np
import pytest
from conftest import child_env

from styletrace.gate import mi

from . import scenes

LIMIT = 120  # seconds: generous for a 32 x 32 render on a loaded 2-core machine, far below "never"


# PNG textures, an EXR normal map, an EXR envmap
@pytest.mark.parametrize("name", ["textured", "normal_bump", "envmap"])
def test_render_with_textures_or_envmap_finishes(name, tmp_path):
    xml = scenes.write_scene(name, tmp_path / name)
    out = tmp_path / "out.exr"
    try:
        r = subprocess.run(
            [
                sys.executable,
                "-m",
                "styletrace",
                "render",
                str(xml),
                "--style",
                "identity",
                "--spp",
                "4",
                "--inner",
                "2",
                "-q",
                "-o",
                str(out),
            ],
            capture_output=True,
            text=True,
            env=child_env(),
            timeout=LIMIT,
        )
    except subprocess.TimeoutExpired:  # subprocess.run has killed the child
        pytest.fail(
            f"styletrace render {name}.xml did not finish within {LIMIT} s (a load deadlock?)"
        )
    assert r.returncode == 0, r.stderr
    img = np.asarray(mi.Bitmap(str(out)), dtype=np.float32)
    assert img.shape[:2] == (scenes.RES, scenes.RES) and np.all(np.isfinite(img)) and img.max() > 0
