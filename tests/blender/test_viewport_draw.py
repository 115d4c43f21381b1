"""What the 3D viewport draws in Rendered shading: a real Blender under Xvfb runs
viewport_draw_blender.py (a small scene, the identity style, 4 spp) and returns the 3D view region's
pixels from Blender's screenshot beside the session's final image, per phase.

The drawn 8-bit pixel is the session's image through the view's colour management (view transform
Standard, display sRGB, exposure 0, gamma 1, no dither): 255 * srgb_oetf(clip(linear)) within
0.5 + DELTA levels; with exposure +1 it is the same of linear x 2 and differs from Standard; an
image drawn upside down or sRGB-encoded before the draw fails that comparison.

Blender shifts a region's pixel space by GLA_PIXEL_OFS = 0.01 px;
`viewport_hooks.draw_view_image` draws its texture at (-0.01, -0.01) to undo it, so each drawn
pixel is its own texel. `DRAW_OFFSET_PX` is the offset the comparison models: 0 (a draw at (0, 0)
would blur each pixel with about 1 % of its left and lower neighbours: 19.8 levels at most on this
image's noise, measured).

Skipped where `blender` or `xvfb-run` is missing, or where Blender's Python is not the minor
version of the .venv whose site-packages it borrows (STYLETRACE_SITE).
"""
import glob
import json
import os
import shutil
import subprocess

import numpy as np
import pytest

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
SCRIPT = os.path.join(HERE, "viewport_draw_blender.py")
SPP = 4
DRAW_OFFSET_PX = 0.0
#: the region's border, rounded corners and the arrows of its hidden regions: left out
MARGIN = 12
# Each step that moves the drawn level before the 8-bit rounding, in levels (x: linear, 0..1):
# the image's RGBA16F texture and the viewport's RGBA16F buffer round x by <= 2^-11 relative
# each: 255 * x * f'(x) * 2^-11 <= 255 * (1.055 / 2.4) * 2^-11 = 0.055 each; OCIO's sRGB LUT
# (srgb_inv.spi1d: 65561 entries over [-0.0097, 40.46], step h = 6.17e-4, linear interpolation):
# 255 * h^2 / 8 * max|f''| (at x = 0.0031308, 2366) = 0.029; its entries if held as half floats:
# 255 * 2^-11 = 0.125. Mesa's llvmpipe (Xvfb's renderer) filters float textures with float weights.
DELTA = 2 * 0.055 + 0.029 + 0.125


def srgb_oetf(x):
    x = np.clip(np.asarray(x, np.float64), 0.0, 1.0)
    return np.where(x <= 0.0031308, 12.92 * x, 1.055 * x ** (1 / 2.4) - 0.055)


def sampled(image, offset):
    """`image` (top row first) sampled `offset` px left of and below each pixel centre, linearly
    filtered, edges clamped: what `draw_texture_2d` at (0, 0) draws at GLA_PIXEL_OFS."""
    image = np.asarray(image, np.float64)
    left = np.concatenate([image[:, :1], image[:, :-1]], 1)
    below = np.concatenate([image[1:], image[-1:]], 0)
    below_left = np.concatenate([left[1:], left[-1:]], 0)
    return ((1 - offset) ** 2 * image + offset * (1 - offset) * (left + below)
            + offset ** 2 * below_left)


def blender_python(blender) -> tuple[int, int]:
    out = subprocess.run([blender, "-b", "--factory-startup", "--python-expr",
                          "import sys; print('PYTHON', *sys.version_info[:2])"],
                         capture_output=True, text=True, timeout=60).stdout
    line = next(ln for ln in out.splitlines() if ln.startswith("PYTHON "))
    return tuple(int(v) for v in line.split()[1:])


@pytest.fixture(scope="module")
def phases(tmp_path_factory):
    blender, xvfb = shutil.which("blender"), shutil.which("xvfb-run")
    if not blender or not xvfb:
        pytest.skip("needs Blender's GUI and Xvfb: apt-get install blender xvfb xauth "
                    "(bash dev.sh test installs them)")
    site = os.environ.get("STYLETRACE_SITE") or next(
        iter(sorted(glob.glob(os.path.join(ROOT, ".venv", "lib", "python3.*", "site-packages")))),
        None)
    if not site or not os.path.isdir(site):
        pytest.skip("no .venv site-packages for Blender to borrow (set STYLETRACE_SITE)")
    venv = os.path.basename(os.path.dirname(site.rstrip("/")))  # python3.11
    own = "python%d.%d" % blender_python(blender)
    if own != venv:
        pytest.skip(f"Blender's Python is {own}, the .venv's is {venv}: its compiled modules "
                    "cannot load in Blender")
    out = tmp_path_factory.mktemp("viewport_draw")
    env = dict(os.environ, STYLETRACE_SITE=site, STYLETRACE_DRAW_OUT=str(out))
    proc = subprocess.run([xvfb, "-a", "-s", "-screen 0 640x400x24", blender, "--factory-startup",
                           "--python", SCRIPT], env=env, capture_output=True, text=True,
                          timeout=180)
    logfile = out / "log.json"
    log = json.loads(logfile.read_text()) if logfile.exists() else {}
    assert proc.returncode == 0 and log, (proc.returncode, log.get("error"), proc.stderr[-3000:])
    print(f"\nBlender {log['blender']}: {log['seconds']} s from the scene to the last phase")
    result = {}
    for name, info in log["phases"].items():
        drawn = np.load(out / f"{name}.png.npy")[..., :3]
        image = np.load(out / f"{name}.image.npy")
        result[name] = (info, drawn, image)
    return result


def error(phase, exposure: float = 0.0) -> np.ndarray:
    """Per inner pixel and channel: |drawn level - 255 * srgb_oetf(2^exposure * the sample)|."""
    info, drawn, image = phase
    x, y, w, h = info["region"]
    assert drawn.shape[:2] == image.shape[:2] == (h, w)
    expected = 255 * srgb_oetf(2.0 ** exposure * sampled(image, DRAW_OFFSET_PX))
    diff = np.abs(drawn.astype(np.float64) - expected)
    return diff[MARGIN:-MARGIN, MARGIN:-MARGIN]


def report(name, diff):
    print(f"{name}: max |drawn - expected| {diff.max():.3f} levels (bound {0.5 + DELTA:.3f}), "
          f"{(diff > 0.5).mean():.2%} of values over 0.5 off, mean {diff.mean():.3f}")


def test_drawn_region_is_the_final_image_colour_managed(phases):
    info = phases["standard"][0]
    assert info["label"] == f"pass 2/2, {SPP} spp" and info["exposure"] == 0.0
    diff = error(phases["standard"])
    report("standard", diff)
    unshifted = np.abs(phases["standard"][1] - 255 * srgb_oetf(phases["standard"][2]))
    print(f"standard, the image itself (no 0.01 px sample): max "
          f"{unshifted[MARGIN:-MARGIN, MARGIN:-MARGIN].max():.3f} levels")
    assert diff.max() <= 0.5 + DELTA


def test_exposure_is_applied_to_the_drawn_pixels(phases):
    info = phases["exposure"][0]
    assert info["exposure"] == 1.0 and info["label"] == f"pass 2/2, {SPP} spp"
    diff = error(phases["exposure"], exposure=1.0)
    report("exposure +1", diff)
    assert diff.max() <= 0.5 + DELTA
    # where linear x 2 moves the level by 2 or more, the drawn pixels differ from Standard's
    image = sampled(phases["standard"][2], DRAW_OFFSET_PX)
    moved = np.abs(np.round(255 * srgb_oetf(2 * image)) - np.round(255 * srgb_oetf(image))) >= 2
    moved = moved[MARGIN:-MARGIN, MARGIN:-MARGIN]
    standard, exposed = (phases[k][1][MARGIN:-MARGIN, MARGIN:-MARGIN] for k in ("standard",
                                                                               "exposure"))
    print(f"exposure +1 moves {moved.mean():.1%} of values by >= 2 levels")
    assert moved.mean() > 0.1 and (standard != exposed)[moved].all()


@pytest.mark.parametrize("name", ["flipped", "encoded"])
def test_a_broken_draw_fails_the_comparison(phases, name):
    diff = error(phases[name])
    report(name, diff)
    assert diff.max() > 0.5 + DELTA and (diff > 0.5 + DELTA).mean() > 0.05


def test_the_display_space_shader_is_not_what_manages_colour(phases):
    """A draw without `bind_display_space_shader` draws the same pixels: `draw_texture_2d` binds
    its own image shader, and Blender's viewport applies the view's colour management when it
    composites the engine's linear buffer. This break cannot fail the comparison."""
    diff = error(phases["unbound"])
    report("unbound", diff)
    assert np.array_equal(phases["unbound"][1], phases["standard"][1])
