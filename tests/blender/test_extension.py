"""The Blender extension zip (`python -m styletrace.blender.extension`): its manifest, checked by
Blender's own extension validator (bl_pkg's blender_ext.py, shipped with bpy), and the wheels it
lists."""
import os
import subprocess
import sys
import zipfile

import bpy
import tomllib

SRC = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", "..", "src"))


def test_extension_zip(tmp_path):
    env = dict(
        os.environ, PYTHONPATH=os.pathsep.join(p for p in (SRC, os.environ.get("PYTHONPATH")) if p)
    )
    run = subprocess.run(
        [sys.executable, "-m", "styletrace.blender.extension", "-o", str(tmp_path)],
        capture_output=True,
        text=True,
        env=env,
        timeout=600,
    )
    assert run.returncode == 0, run.stderr
    path = run.stdout.strip().splitlines()[-1]
    with zipfile.ZipFile(path) as z:
        names = set(z.namelist())
        manifest = tomllib.loads(z.read("blender_manifest.toml").decode())
        entry = z.read("__init__.py").decode()
    assert manifest["id"] == "styletrace" and manifest["type"] == "add-on"
    assert tuple(int(v) for v in manifest["blender_version_min"].split(".")) <= (4, 2, 0)
    wheels = [w.removeprefix("./") for w in manifest["wheels"]]
    assert set(wheels) <= names and len(wheels) == 7
    for dist in (
        "styletrace-",
        "mitsuba-3.9.1-",
        "drjit-1.5.0-",
        "tqdm-",
        "pyoidn-2.5.1.0-",
        "cffi-",
        "pycparser-",
    ):
        assert any(os.path.basename(w).startswith(dist) for w in wheels), dist
    assert "from styletrace.blender import register" in entry
    validator = os.path.join(
        bpy.utils.system_resource("SCRIPTS"), "addons_core", "bl_pkg", "cli", "blender_ext.py"
    )
    assert os.path.isfile(validator), "bpy ships Blender's extension validator"
    check = subprocess.run(
        [sys.executable, validator, "validate", path], capture_output=True, text=True
    )
    assert check.returncode == 0, check.stdout + check.stderr
