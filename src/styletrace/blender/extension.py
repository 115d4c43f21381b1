"""Build the Blender extension (Blender 4.2+): a zip with `blender_manifest.toml`, the add-on's entry module and
the wheels it needs (styletrace itself, Mitsuba, Dr.Jit, tqdm, and pyoidn with cffi for Denoise; numpy
comes with Blender).

    python -m styletrace.blender.extension -o DIR [--platform linux-x64] [--python 3.11]

Blender installs it from Edit -> Preferences -> Get Extensions -> Install from Disk (or
`blender --command extension install-file -r user_default FILE.zip`). Wheels are platform-specific,
so each zip is for one platform; Blender 4.2 to 5.0 embed Python 3.11. Runs without Blender (does
not import bpy).
"""  # noqa: E501 (the first line is the command's --help description, kept as it was)
from __future__ import annotations

import argparse
import os
import shutil
import subprocess
import sys
import tempfile
import zipfile

from styletrace import __version__

#: Blender's platform names -> pip's platform tags for the wheels
PLATFORMS = {
    "linux-x64": [
        "manylinux_2_28_x86_64",
        "manylinux_2_27_x86_64",
        "manylinux_2_17_x86_64",
        "manylinux2014_x86_64",
    ],
    "windows-x64": ["win_amd64"],
    "macos-arm64": [
        "macosx_11_0_arm64",
        "macosx_12_0_arm64",
        "macosx_13_0_arm64",
        "macosx_14_0_arm64",
    ],
}
#: what the add-on needs beyond Blender's own Python and numpy (pinned as in constraints.txt)
REQUIREMENTS = ["mitsuba==3.9.1", "drjit==1.5.0", "tqdm==4.70.1",
                # Denoise (Intel Open Image Denoise, denoise/finishers.py): ~50-90 MB per platform
                "pyoidn==2.5.1.0", "cffi==2.1.1", "pycparser==3.12"]
ADDON_ID = "styletrace"

ENTRY = '''"""styletrace as a Blender extension: the add-on lives in the bundled styletrace wheel (styletrace.blender)."""


def register():
    from styletrace.blender import register as _register
    _register()


def unregister():
    from styletrace.blender import unregister as _unregister
    _unregister()
'''  # noqa: E501 (the entry module's text, as it was)


def manifest(wheels: list[str], platform: str) -> str:
    """The extension's `blender_manifest.toml`.

    Args:
        wheels: the wheel files' names (listed sorted, under ./wheels/).
        platform: Blender's platform name (a key of PLATFORMS).

    Returns:
        The TOML text.
    """
    listed = ",\n".join(f'  "./wheels/{w}"' for w in sorted(wheels))
    return f'''schema_version = "1.0.0"
id = "{ADDON_ID}"
version = "{__version__}"
name = "styletrace"
tagline = "Stylized global illumination as a function of expectation"
maintainer = "styletrace developers"
type = "add-on"
website = "https://doi.org/10.1145/3658161"
tags = ["Render"]
blender_version_min = "4.2.0"
license = ["SPDX:BSD-3-Clause"]
platforms = ["{platform}"]
wheels = [
{listed}
]

[permissions]
files = "Write exported scenes and the look-development buffer"
'''


def _run(cmd: list[str]) -> None:
    proc = subprocess.run(cmd, capture_output=True, text=True)
    if proc.returncode != 0:
        tail = (proc.stderr or proc.stdout).strip().splitlines()[-1:] or ["failed"]
        raise SystemExit(f"styletrace extension: {' '.join(cmd[:4])} ...: {tail[0]}")


def project_root() -> str:
    """The source tree's root (where pyproject.toml is), to build the styletrace wheel from."""
    here = os.path.dirname(os.path.abspath(__file__))
    root = os.path.abspath(os.path.join(here, "..", "..", ".."))
    if not os.path.isfile(os.path.join(root, "pyproject.toml")):
        raise SystemExit(
            "styletrace extension: build from a source checkout (pyproject.toml not found)"
        )
    return root


def _source_copy(tmp: str) -> str:
    """A copy of the source tree to build the wheel in: setuptools leaves a build/ folder where
    it builds."""
    root, dest = project_root(), os.path.join(tmp, "source")
    shutil.copytree(os.path.join(root, "src"), os.path.join(dest, "src"),
                    ignore=shutil.ignore_patterns("__pycache__", "*.egg-info"))
    for name in ("pyproject.toml", "README.md", "LICENSE"):
        shutil.copy2(os.path.join(root, name), dest)
    return dest


def build_extension(out_dir: str, platform: str = "linux-x64", python: str = "3.11") -> str:
    """Write `styletrace-VERSION-PLATFORM.zip` into `out_dir`: the manifest, the entry module and
    the wheels (styletrace built from this checkout, REQUIREMENTS downloaded with pip).

    Args:
        out_dir: the folder (made if missing). platform: a key of PLATFORMS.
        python: Blender's Python version (3.11 for Blender 4.2 to 5.0).

    Returns:
        The zip's path.

    Raises:
        SystemExit: an unknown platform, no source checkout, or a failing pip (one line).
    """
    if platform not in PLATFORMS:
        raise SystemExit(
            f"styletrace extension: unknown platform '{platform}': one of {', '.join(PLATFORMS)}"
        )
    os.makedirs(out_dir, exist_ok=True)
    with tempfile.TemporaryDirectory() as tmp:
        wheels = os.path.join(tmp, "wheels")
        os.makedirs(wheels)
        _run(
            [
                sys.executable,
                "-m",
                "pip",
                "wheel",
                "--no-deps",
                "-q",
                "-w",
                wheels,
                _source_copy(tmp),
            ]
        )
        cmd = [sys.executable, "-m", "pip", "download", "-q", "--no-deps", "--only-binary=:all:",
               "--python-version", python, "-d", wheels]
        for tag in PLATFORMS[platform]:
            cmd += ["--platform", tag]
        _run(cmd + REQUIREMENTS)
        names = sorted(os.listdir(wheels))
        path = os.path.join(out_dir, f"{ADDON_ID}-{__version__}-{platform}.zip")
        with zipfile.ZipFile(path + ".tmp", "w", zipfile.ZIP_DEFLATED) as z:
            z.writestr("blender_manifest.toml", manifest(names, platform))
            z.writestr("__init__.py", ENTRY)
            for name in names:
                z.write(os.path.join(wheels, name), f"wheels/{name}")
        os.replace(path + ".tmp", path)
    return path


def extension_main(argv: list[str] | None = None) -> int:
    """`python -m styletrace.blender.extension`: build the extension zip and print its path.

    Args:
        argv: the arguments (None: sys.argv[1:]): -o DIR, --platform, --python.

    Returns:
        The exit status, 0.
    """
    parser = argparse.ArgumentParser(
        prog="python -m styletrace.blender.extension", description=__doc__.split("\n")[0]
    )
    parser.add_argument(
        "-o", "--output", required=True, help="folder to write the extension zip into"
    )
    parser.add_argument("--platform", default="linux-x64", choices=sorted(PLATFORMS))
    parser.add_argument(
        "--python", default="3.11", help="Blender's Python version (3.11 for Blender 4.2 to 5.0)"
    )
    args = parser.parse_args(argv)
    print(build_extension(args.output, args.platform, args.python))
    return 0


if __name__ == "__main__":
    sys.exit(extension_main())
