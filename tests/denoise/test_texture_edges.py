"""A texture edge inside a pixel: each camera sample takes D times its own albedo
(denoise/expectation.py, `remodulate`).

A diffuse checkerboard plane facing the camera under a constant environment L and nothing else
has exitant radiance albedo(x) * L everywhere: E[L] jumps with the texture and nothing else. In a
pixel that a texture edge crosses, M mixes the two albedos, and so does OIDN's D; with the
remodulation each sample's D is its own albedo times L again, without it the samples on either
side share the pixel's mixture, off by the albedo contrast (dark 0.15 against bright 0.8). Both
where the style is applied: at the camera samples (coverage 0, `at_samples`) and at coverage
points (`coverage.CoverageIntegrator`, the lookup in the kernel)."""
import numpy as np
import pytest
from helpers.denoise_edges import denoised_identity

from styletrace.denoise import expectation as X
from styletrace.frontends import api
from styletrace.gate import mi

RES, SKY = 48, 0.7
DARK, BRIGHT = 0.15, 0.8


def scene():
    T = mi.ScalarTransform4f
    return api.load_scene(
        {
            "type": "scene",
            "sensor": {
                "type": "perspective",
                "fov": 30,
                "to_world": T().look_at(origin=[0, 0, 4], target=[0, 0, 0], up=[0, 1, 0]),
                "film": {
                    "type": "hdrfilm",
                    "width": RES,
                    "height": RES,
                    "rfilter": {"type": "box"},
                },
            },
            "plane": {
                "type": "rectangle",
                "to_world": T().scale(2.0),
                "bsdf": {
                    "type": "diffuse",
                    "reflectance": {
                        "type": "checkerboard",
                        "color0": {"type": "rgb", "value": [DARK] * 3},
                        "color1": {"type": "rgb", "value": [BRIGHT] * 3},
                        "to_uv": T().rotate([0, 0, 1], 17).scale([5.3, 5.3, 1]),
                    },
                },
            },
            "sky": {"type": "constant", "radiance": {"type": "rgb", "value": [SKY] * 3}},
        }
    )


def edge_samples_error(remodulate, monkeypatch, coverage):
    """Relative error of D at the samples of pixels whose samples see both albedos, per sample;
    `remodulate` turns on both things that keep a sample's own albedo: the remodulation and the
    lookup's own-albedo test."""
    monkeypatch.setattr(X, "REMODULATE", remodulate)
    monkeypatch.setattr(X, "OWN_ALBEDO", remodulate)
    got = denoised_identity(scene(), coverage=coverage)
    own = got.albedo[:, 0]
    edges, mixed = got.in_pixels_with_both(own < 0.5, own > 0.5, RES * RES)
    pick = mixed & got.found
    assert edges > 100, "the texture crosses too few pixels: nothing is tested"
    want = own[pick] * SKY
    return np.abs(got.denoised()[pick] - want) / want


@pytest.mark.parametrize("coverage", [0, 16])
def test_samples_on_a_texture_edge_take_their_own_albedo(monkeypatch, coverage):
    """With the remodulation and the own-albedo lookup the median relative error of D at
    edge-pixel samples is below 0.1; without them above 0.3 (measured 0.03 and 0.55 at the camera
    samples; the mixture of 0.15 and 0.8 is off by far more on either side): the test can fail.
    (Either one alone mostly suffices here, where the light is the same on both sides: the
    own-albedo lookup alone measured 0.02.)"""
    with_, without = (
        np.median(edge_samples_error(r, monkeypatch, coverage)) for r in (True, False)
    )
    print(f"coverage {coverage}: median relative error {with_:.3f} remodulated, {without:.3f} not")
    assert with_ < 0.1
    assert without > 0.3
