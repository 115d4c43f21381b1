"""A GUI Blender borrows styletrace's dependencies from a venv: its own Python has none of them.

Used by the scripts that Blender itself runs (docs/make_blender_*.py,
benchmarks/blender_viewport.py, tests/blender/viewport_draw_blender.py), after they put the
repository's src/ on sys.path. Only the packages named are linked, so nothing else of the venv
(its `bpy` wheel) shadows Blender's modules. Blender's Python must be the venv's minor version.
Standard library only: numpy is not there yet.
"""
from __future__ import annotations

import glob
import os
import sys
import tempfile

#: styletrace's run-time dependencies, PIL for the screenshots, and the denoiser (pyoidn calls OIDN
#: through cffi)
PACKAGES = ("numpy", "numpy.libs", "mitsuba", "drjit", "tqdm", "PIL", "pillow.libs")
DENOISER = ("pyoidn", "cffi", "_cffi_backend*.so", "pycparser")


def borrow_site(root: str, names: tuple[str, ...] = PACKAGES + DENOISER,
                links: str | None = None) -> str:
    """Link `names` from the venv's site-packages into a folder and put it first on sys.path.

    Args:
        root: the repository; the venv is $STYLETRACE_SITE, else root/.venv's site-packages.
        names: file-name patterns in site-packages (a missing one is skipped).
        links: the folder of links (made if missing); None: a new temporary folder.
    Returns:
        The folder of links.
    """
    version = f"python{sys.version_info[0]}.{sys.version_info[1]}"
    site = os.path.abspath(os.environ.get(
        "STYLETRACE_SITE", os.path.join(root, ".venv", "lib", version, "site-packages")))
    links = links or tempfile.mkdtemp(prefix="styletrace_site_")
    os.makedirs(links, exist_ok=True)
    for name in names:
        for path in glob.glob(os.path.join(site, name)):
            os.symlink(path, os.path.join(links, os.path.basename(path)))
    sys.path.insert(0, links)
    return links
