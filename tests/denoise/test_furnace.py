"""The denoised expectation of a constant-radiance furnace is the constant.

A diffuse sphere of albedo rho under a constant environment E has exitant radiance rho*E at every
point (scene/builtin.py), so the per-pixel expectation M inside the silhouette is rho*E plus the
children's noise, and a correct denoiser must return the constant. Tolerances, from the noisy M
itself (sigma: its per-pixel standard deviation over the N interior pixels, per channel):
- the mean of D over the interior lies within Z = 4 standard errors sigma/sqrt(N) of rho*E (a filter
  that keeps a constant and averages noise keeps the noisy mean, whose standard error that is; 4: a
  two-sided 6e-5 test);
- the RMS of D - rho*E over the interior is below sigma/4: the denoiser removed at least three
  quarters of the noise's standard deviation (a no-op, or a denoiser fed the wrong image, leaves
  sigma).
The same holds for D where the style meets it at coverage points (`denoise.coverage`: D looked up in
the kernel at 16 stratified points per pixel), with the same tolerances, over the points of the
interior pixels.
"""
import numpy as np

from styletrace.denoise import expectation as X
from styletrace.frontends import api
from styletrace.pipeline.denoising import Denoising
from styletrace.pipeline.passes import Shot
from styletrace.scene.builtin import FURNACE_ALBEDO, FURNACE_RADIANCE

RES, Z = 64, 4.0


def interior(buf):
    """Pixels whose every camera sample hit the sphere, and whose 8 neighbours' did too (no
    silhouette)."""
    a = buf.arrays
    hit = np.bincount(a["pixel"][a["slot"] >= 0], minlength=RES * RES).reshape(RES, RES) == buf.spp
    inner = hit.copy()
    for dy in (-1, 0, 1):
        for dx in (-1, 0, 1):
            inner &= np.roll(np.roll(hit, dy, 0), dx, 1)
    return inner


def test_denoised_furnace_is_the_constant():
    scene = api.load_scene("furnace", RES, RES)
    _, buf = X.render_denoised_expectation(
        Shot(scene, api.make_integrator(style="identity", inner=1), 1, 3),
        Denoising("expectation", coverage=0),
    )
    exact = np.asarray(FURNACE_ALBEDO) * FURNACE_RADIANCE
    mask = interior(buf)
    assert mask.sum() > 500
    noisy = X.expectation(buf)[mask].astype(np.float64)
    d = X.attach(buf, Shot(scene, None, 1, 3))[0][mask].astype(np.float64)  # D per pixel
    sigma = noisy.std(0, ddof=1)
    assert np.all(sigma > 0.05 * exact), "the furnace's children carry no noise: nothing is tested"
    se = sigma / np.sqrt(mask.sum())
    assert np.all(np.abs(d.mean(0) - exact) < Z * se), f"mean {d.mean(0)} vs {exact}, se {se}"
    rms = np.sqrt(((d - exact) ** 2).mean(0))
    assert np.all(rms < sigma / 4), f"RMS {rms} vs noise sigma {sigma}"


def test_denoised_furnace_is_the_constant_at_coverage_points():
    scene = api.load_scene("furnace", RES, RES)
    integ = api.make_integrator(style="identity", inner=1)
    shot = Shot(scene, integ, 1, 3)
    _, cam = X.render_denoised_expectation(shot, Denoising("expectation", coverage=0))
    _, cover = X.render_denoised_expectation(shot, Denoising("expectation", coverage=16))
    assert cover.spp == 16 and cover.source.spp == 1
    exact = np.asarray(FURNACE_ALBEDO) * FURNACE_RADIANCE
    mask = interior(cam).ravel()
    sigma = X.expectation(cam)[mask.reshape(RES, RES)].astype(np.float64).std(0, ddof=1)
    a = cover.arrays
    pick = mask[a["pixel"]] & (a["slot"] >= 0)
    d = a["mean"][:, pick].T.astype(np.float64)  # D at each point
    # the points of a pixel share its D: the pixels are the independent units
    se = sigma / np.sqrt(mask.sum())
    assert np.all(np.abs(d.mean(0) - exact) < Z * se), f"mean {d.mean(0)} vs {exact}, se {se}"
    rms = np.sqrt(((d - exact) ** 2).mean(0))
    assert np.all(rms < sigma / 4), f"RMS {rms} vs noise sigma {sigma}"
