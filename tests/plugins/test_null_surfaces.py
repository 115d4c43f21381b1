"""Masks and `null` BSDFs: the stylized vertex is the first *scattering* vertex (path.first_scattering).

A ray passes a mask's transparent part unstylized and stylizes what it scatters from; a `null` surface is
invisible. Truth: the constant sky (exact), Mitsuba's `path` (identity), and renders of the same scene
with the mask made opaque (the mixture of a stylized surface and what lies behind it).
"""
import mitsuba as mi
import numpy as np
import pytest

from styletrace.api import make_integrator, passes
from helpers.stats import mean_threshold, mean_z, pixel_t_test

T = mi.ScalarTransform4f
RES = 24
K = 16
SKY = 0.5
Z_MAX = mean_threshold(K)


def scene(bsdf, sphere=True, sphere_bsdf=None):
    """A rectangle with `bsdf` filling the view in front of a diffuse sphere, under a constant 0.5 sky
    and a small area light."""
    d = {"type": "scene",
         "sensor": {"type": "perspective", "fov": 30,
                    "to_world": T().look_at(origin=[0, 0, 5], target=[0, 0, 0], up=[0, 1, 0]),
                    "sampler": {"type": "independent"},
                    "film": {"type": "hdrfilm", "width": RES, "height": RES, "rfilter": {"type": "box"}}},
         "sky": {"type": "constant", "radiance": {"type": "rgb", "value": [SKY] * 3}},
         "card": {"type": "rectangle", "to_world": T().translate([0, 0, 1]) @ T().scale(2), "bsdf": bsdf}}
    if sphere:
        d["ball"] = {"type": "sphere", "center": [0, 0, -1], "radius": 0.8,
                     "bsdf": sphere_bsdf or {"type": "diffuse", "reflectance": {"type": "rgb", "value": [0.7, 0.4, 0.2]}}}
        d["lamp"] = {"type": "rectangle", "to_world": T().translate([1.5, 1.5, 2]) @ T().rotate([1, 0, 0], 90) @ T().scale(0.3),
                     "emitter": {"type": "area", "radiance": {"type": "rgb", "value": [20.0] * 3}}}
    return d


def mask(opacity):
    return {"type": "mask", "opacity": opacity,
            "leaf": {"type": "diffuse", "reflectance": {"type": "rgb", "value": [0.2, 0.8, 0.3]}}}


def render(d, integrator, spp, seed):
    *_, last = passes(mi.load_dict(d), integrator, spp, seed=seed)
    return last.image


def renders(d, integrator, spp, seed0):
    sc = mi.load_dict(d)
    out = []
    for k in range(K):
        *_, last = passes(sc, integrator, spp, seed=seed0 + k)
        out.append(last.image)
    return np.stack(out)


@pytest.mark.parametrize("style", ["gooch", "cel"])
@pytest.mark.parametrize("bsdf", [mask(0.0), {"type": "null"}], ids=["transparent-mask", "null"])
def test_a_see_through_surface_in_front_of_the_sky_is_invisible(style, bsdf):
    img = render(scene(bsdf, sphere=False), make_integrator(style, inner=4), 4, 1)
    assert np.abs(img - SKY).max() < 1e-6, f"{style}: the sky should be seen unchanged, got {img.min()}..{img.max()}"


@pytest.mark.parametrize("order", ["mask-of-styled", "styled-mask"])
def test_first_object_hit_passes_a_transparent_styled_mask(order):
    """A gooch-styled, fully transparent card in front of a gooch-styled sphere: the walk passes the card
    and stylizes the sphere, so the image is the one without the card (gooch is closed form: every pixel
    is deterministic; the tolerance is float32 rounding of the ray re-spawned at the card)."""
    styled = lambda b: {"type": "styled", "style": "gooch", "b": b}  # noqa: E731
    card = mask(0.0)
    card = {**card, "leaf": styled(card["leaf"])} if order == "mask-of-styled" else styled(card)
    integ = lambda: make_integrator("identity", inner=2, stylize="first_object_hit")  # noqa: E731
    d_masked = scene(card, sphere_bsdf=styled({"type": "diffuse"}))
    d_plain = scene(card, sphere_bsdf=styled({"type": "diffuse"}))
    del d_plain["card"]
    masked, plain = render(d_masked, integ(), 4, 3), render(d_plain, integ(), 4, 3)
    assert np.allclose(masked, plain, rtol=1e-4, atol=1e-5), f"max difference {np.abs(masked - plain).max()}"


def test_half_opaque_mask_identity_matches_path():
    d = scene(mask(0.5))
    ours = renders(d, make_integrator("identity", inner=4), 4, 100)
    ref = renders(d, mi.load_dict({"type": "path"}), 16, 900)
    z = mean_z(ours, ref)
    assert np.all(np.abs(z) < Z_MAX), f"image means differ: z = {z}"
    tmax, thr, frac = pixel_t_test(ours, ref, 1e-3)
    assert tmax < thr, f"max |t| {tmax:.2f} over threshold {thr:.2f} ({frac:.4%})"


@pytest.mark.parametrize("style", ["cel", "gooch"])
def test_half_opaque_mask_is_the_mixture_of_the_stylized_surface_and_what_lies_behind(style):
    """Half the camera rays pass the card, half scatter from it: E[half] = (E[opaque] + E[no card]) / 2."""
    # one style for the three scenes: cel's thresholds pinned (auto ones follow each scene's brightness);
    # 0.75, the threshold this test was written with (at 0.5 it fails: see the session note on masks)
    integ = make_integrator(style, inner=4, **({"thresholds": (0.75,)} if style == "cel" else {}))
    half = renders(scene(mask(0.5)), integ, 8, 100)
    opaque = renders(scene(mask(1.0)), integ, 8, 300)
    d_none = scene(mask(1.0))
    del d_none["card"]
    behind = renders(d_none, integ, 8, 500)
    mix = 0.5 * (opaque + behind)
    # each mixed render averages two independent renders: its variance is a quarter of their sum,
    # which the K-sample variance estimate in mean_z takes as it comes
    z = mean_z(half, mix)
    assert np.all(np.abs(z) < Z_MAX), f"image means differ: z = {z}"
