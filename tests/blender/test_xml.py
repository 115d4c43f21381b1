"""File -> Export -> Mitsuba XML, rendered by `styletrace render`, gives F12's image with the
same seed and pass split: the exported file holds the same scene (PLY meshes and EXR images
written from the same in-memory description) and the render settings as its `stylized`
integrator."""
import os
import subprocess
import sys

import bpy
import numpy as np
import pytest
import scenes as S

SRC = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", "..", "src"))


def child_env():
    """Our source tree first on the subprocess's PYTHONPATH (as tests/conftest.py's child_env)."""
    return dict(
        os.environ, PYTHONPATH=os.pathsep.join(p for p in (SRC, os.environ.get("PYTHONPATH")) if p)
    )


@pytest.mark.parametrize("name", ["textured_plane", "instanced"])
def test_exported_xml_renders_the_f12_image(name, tmp_path):
    S.SCENES[name](32)
    f12 = S.styletrace(str(tmp_path / "f12.exr"), 8, seed=11, pass_spp=4, style="cel")["Combined"][
        ..., :3
    ]
    xml = str(tmp_path / "scene.xml")
    assert bpy.ops.styletrace.export_xml(filepath=xml) == {"FINISHED"}
    # the counts the export reports (Samples 16 with Camera samples 8: 8 x 2 children)
    from styletrace.blender.operators import command_line
    line = command_line(xml, bpy.context.scene.styletrace)
    assert f"{xml} --samples 16 --spp 8 --seed 11" in line, line
    counts = ["--samples", "16", "--spp", "8"]
    text = open(xml).read()
    assert '<integrator type="stylized">' in text and 'type="ply"' in text
    if name == "instanced":
        # one shapegroup per instanced object (cube, sphere), one instance per object per placement
        # (3)
        assert text.count('type="shapegroup"') == 2 and text.count('type="instance"') == 6
    out = str(tmp_path / "cli.exr")
    run = subprocess.run(
        [
            sys.executable,
            "-m",
            "styletrace",
            "render",
            xml,
            *counts,
            "--seed",
            "11",
            "--pass-spp",
            "4",
            "-o",
            out,
        ],
        capture_output=True,
        text=True,
        env=child_env(),
        timeout=300,
    )
    assert run.returncode == 0, run.stderr
    import mitsuba as mi
    cli = np.array(mi.Bitmap(out), dtype=np.float32)[..., :3]
    assert f12.shape == cli.shape
    assert np.abs(f12).max() > 0
    np.testing.assert_allclose(cli, f12, rtol=1e-5, atol=1e-6)
    # and `--ray` (a local Ray instance) renders the same file to the same image
    if name == "instanced":
        ray_out = str(tmp_path / "ray.exr")
        run = subprocess.run(
            [
                main_python(),
                "-m",
                "styletrace",
                "render",
                xml,
                *counts,
                "--seed",
                "11",
                "--pass-spp",
                "4",
                "--ray",
                "-o",
                ray_out,
            ],
            capture_output=True,
            text=True,
            env=child_env(),
            timeout=600,
        )
        assert run.returncode == 0, run.stderr
        np.testing.assert_allclose(
            np.array(mi.Bitmap(ray_out), dtype=np.float32)[..., :3], f12, rtol=1e-5, atol=1e-6
        )


def main_python():
    """The project's main environment (dev.sh's STYLETRACE_VENV, .venv): Ray is an extra of that
    one; the Blender environment (numpy < 2 for bpy) does not carry it."""
    root = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))
    venv = os.environ.get("STYLETRACE_VENV", ".venv")
    python = os.path.join(
        venv if os.path.isabs(venv) else os.path.join(root, venv), "bin", "python"
    )
    assert os.path.exists(python), (
        f"no main environment at {python}: run `bash dev.sh test` (it builds both)"
    )
    return python
