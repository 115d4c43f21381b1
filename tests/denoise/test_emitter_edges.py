"""A light's edge inside a pixel: the reflected part of E[L] is denoised and each camera sample's
own emission is added back (denoise/expectation.py, `own_surface`, EMISSION_APART).

A diffuse plane of albedo A facing the camera under a constant environment L, with a square area
light of the same albedo lying on it (a hair in front): E[L] is A L everywhere plus the light's
radiance Le on the square. Albedo and normal are the same on both sides of the light's edge, so
no guide separates them; in a pixel the edge crosses, M mixes Le into the plane's samples. With
the emission apart the plane's samples there get A L again; without it they take a share of Le.
Both at the camera samples (coverage 0) and at coverage points."""
import numpy as np
import pytest
from helpers.denoise_edges import denoised_identity

from styletrace.denoise import expectation as X
from styletrace.frontends import api
from styletrace.gate import mi

RES, SKY, ALBEDO, LE = 48, 0.7, 0.5, 6.0


def scene():
    T = mi.ScalarTransform4f
    grey = {"type": "diffuse", "reflectance": {"type": "rgb", "value": [ALBEDO] * 3}}
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
            "plane": {"type": "rectangle", "to_world": T().scale(2.0), "bsdf": grey},
            "light": {
                "type": "rectangle",
                "to_world": T().translate([0.05, -0.03, 1e-3]).rotate([0, 0, 1], 17).scale(0.5),
                "bsdf": grey,
                "emitter": {"type": "area", "radiance": {"type": "rgb", "value": [LE] * 3}},
            },
            "sky": {"type": "constant", "radiance": {"type": "rgb", "value": [SKY] * 3}},
        }
    )


def plane_samples_error(apart, monkeypatch, coverage):
    """Relative error of D at the plane's (not the light's) samples in pixels the light's edge
    crosses."""
    monkeypatch.setattr(X, "EMISSION_APART", apart)
    got = denoised_identity(scene(), coverage=coverage)
    lit = got.emission[:, 0] > 0
    edges, mixed = got.in_pixels_with_both(lit & got.found, ~lit & got.found, RES * RES)
    assert edges > 40, "the light's edge crosses too few pixels: nothing is tested"
    np.testing.assert_allclose(got.emission[lit, 0], LE)  # the emission found is the light's own
    pick = mixed & got.found & ~lit
    want = ALBEDO * SKY
    return np.abs(got.denoised()[pick] - want) / want


@pytest.mark.parametrize("coverage", [0, 16])
def test_plane_samples_beside_a_light_do_not_take_its_emission(monkeypatch, coverage):
    """Median relative error below 0.1 with the emission apart, above 0.5 without (measured: see
    the assert messages; a share of Le = 6 against A L = 0.35 is far off)."""
    with_ = np.median(plane_samples_error(True, monkeypatch, coverage))
    without = np.median(plane_samples_error(False, monkeypatch, coverage))
    assert with_ < 0.1, with_
    assert without > 0.5, without
    print(f"median relative error: {with_:.3f} with the emission apart, {without:.3f} without")
