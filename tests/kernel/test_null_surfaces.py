"""Masks and `null` BSDFs: the stylized vertex is the first *scattering* vertex
(path.first_scattering).

A ray passes a mask's transparent part unstylized and stylizes what it scatters from; a `null`
surface is invisible. Truth: the constant sky (exact), Mitsuba's `path` (identity), and renders of
the same scene with the mask made opaque (the mixture of a stylized surface and what lies behind
it).
"""
import numpy as np
import pytest
from helpers.stats import mean_threshold, mean_z, pixel_t_test

from styletrace.frontends.api import make_integrator, passes
from styletrace.gate import mi

T = mi.ScalarTransform4f
RES = 24
K = 16
SKY = 0.5
Z_MAX = mean_threshold(K)
#: camera samples per pixel and render where first_n_hits at depth 2 meets the per-pixel t-test (see
#: its use)
DEEP_SPP = 128


def scene(bsdf, sphere=True, sphere_bsdf=None):
    """A rectangle with `bsdf` filling the view in front of a diffuse sphere, under a constant
    0.5 sky and a small area light."""
    d = {
        "type": "scene",
        "sensor": {
            "type": "perspective",
            "fov": 30,
            "to_world": T().look_at(origin=[0, 0, 5], target=[0, 0, 0], up=[0, 1, 0]),
            "sampler": {"type": "independent"},
            "film": {"type": "hdrfilm", "width": RES, "height": RES, "rfilter": {"type": "box"}},
        },
        "sky": {"type": "constant", "radiance": {"type": "rgb", "value": [SKY] * 3}},
        "card": {
            "type": "rectangle",
            "to_world": T().translate([0, 0, 1]) @ T().scale(2),
            "bsdf": bsdf,
        },
    }
    if sphere:
        d["ball"] = {
            "type": "sphere",
            "center": [0, 0, -1],
            "radius": 0.8,
            "bsdf": sphere_bsdf
            or {"type": "diffuse", "reflectance": {"type": "rgb", "value": [0.7, 0.4, 0.2]}},
        }
        d["lamp"] = {
            "type": "rectangle",
            "to_world": T().translate([1.5, 1.5, 2]) @ T().rotate([1, 0, 0], 90) @ T().scale(0.3),
            "emitter": {"type": "area", "radiance": {"type": "rgb", "value": [20.0] * 3}},
        }
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
    assert np.abs(img - SKY).max() < 1e-6, (
        f"{style}: the sky should be seen unchanged, got {img.min()}..{img.max()}"
    )


@pytest.mark.parametrize("order", ["mask-of-styled", "styled-mask"])
def test_first_object_hit_passes_a_transparent_styled_mask(order):
    """A gooch-styled, fully transparent card in front of a gooch-styled sphere: the walk passes
    the card and stylizes the sphere, so the image is the one without the card (gooch is closed
    form: every pixel is deterministic; the tolerance is float32 rounding of the ray re-spawned
    at the card)."""
    styled = lambda b: {"type": "styled", "style": "gooch", "b": b}  # noqa: E731
    card = mask(0.0)
    card = {**card, "leaf": styled(card["leaf"])} if order == "mask-of-styled" else styled(card)
    integ = lambda: make_integrator("identity", inner=2, stylize="first_object_hit")  # noqa: E731
    d_masked = scene(card, sphere_bsdf=styled({"type": "diffuse"}))
    d_plain = scene(card, sphere_bsdf=styled({"type": "diffuse"}))
    del d_plain["card"]
    masked, plain = render(d_masked, integ(), 4, 3), render(d_plain, integ(), 4, 3)
    assert np.allclose(masked, plain, rtol=1e-4, atol=1e-5), (
        f"max difference {np.abs(masked - plain).max()}"
    )


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
    """Half the camera rays pass the card, half scatter from it: E[half] = (E[opaque] + E[no
    card]) / 2."""
    # one style for the three scenes: cel's thresholds pinned (auto ones follow each scene's
    # brightness); 0.75, the threshold this test was written with. The three scenes light the sphere
    # differently (the lamp shines through the card onto it: half, none, all of it), so this mixture
    # is a reference only where cel puts those lightings in one band;
    # test_half_opaque_mask_stylizes_each_branch_of_the_path has an exact one at thresholds 0.5 and
    # 0.75
    fixed = {"thresholds": (0.75,), "levels": (0.4, 0.95)}
    integ = make_integrator(style, inner=4, **(fixed if style == "cel" else {}))
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


def card_over_white_sky(opacity):
    """The card alone (grey albedo 0.6, filling the view) under a white sky of radiance 1: its
    opaque part's exitant radiance is E = 0.6 exactly, and what lies behind it is the sky, seen
    unstylized."""
    d = scene(
        {
            "type": "mask",
            "opacity": opacity,
            "leaf": {"type": "diffuse", "reflectance": {"type": "rgb", "value": [0.6] * 3}},
        },
        sphere=False,
    )
    d["sky"]["radiance"]["value"] = [1.0] * 3
    return d


@pytest.mark.parametrize("threshold", [0.5, 0.75])
def test_half_opaque_mask_stylizes_each_branch_of_the_path(threshold):
    """What g sees at a half-opaque card (docs/scenes.md, masks): the pass is part of the path,
    so half the camera rays see the sky (unstylized: 1) and half stop at the card, whose stylized
    value is g of the card's own (opaque part's) expected radiance, E = 0.6, estimated by the
    same children as on the opaque card. The image mean is then 0.5 (opaque card's) + 0.5; g of
    the alpha blend, cel(0.8) = 0.95 at both thresholds, would be far off at 0.75 (0.70
    expected). The opaque card's renders are the brute-force value of its branch at 0.5, where 16
    inner samples of E = 0.6 cross the threshold now and then (the direct estimator's bias, the
    same on both cards); at 0.75 they never reach it (measured: every pixel exactly 0.4 in 16 x
    16 x 64 samples), so the analytic 0.5 * 0.4 + 0.5 * 1 = 0.7 is checked as well. Tolerances:
    Student's t from the spread of K independent renders per side (mean_z). Before the stylized
    vertex sampled its opaque part alone, half its children went through the card and were
    dropped (weight 2 on the rest): the image means were 0.921 at 0.5 and 0.731 at 0.75."""
    integ = make_integrator("cel", inner=16, thresholds=(threshold,), levels=(0.4, 0.95))
    half = renders(card_over_white_sky(0.5), integ, 16, 100)
    opaque = renders(card_over_white_sky(1.0), integ, 16, 300)
    z = mean_z(half, 0.5 * opaque + 0.5)
    assert np.all(np.abs(z) < Z_MAX), (
        f"image means {half.mean():.4f} vs {0.5 * opaque.mean() + 0.5:.4f}: z = {z}"
    )
    if threshold == 0.75:
        np.testing.assert_allclose(opaque, 0.4, rtol=1e-6)  # I * level / u in float32
        means = half.reshape(K, -1, 3).mean(axis=1).astype(np.float64)
        t = (means.mean(axis=0) - 0.7) / (means.std(axis=0, ddof=1) / np.sqrt(K))
        # one sample of K renders: K - 1 degrees of freedom; mean_threshold(K // 2) takes K - 2 (a
        # little wider)
        assert np.all(np.abs(t) < mean_threshold(K // 2)), (
            f"image mean {half.mean():.4f} vs 0.7: t = {t}"
        )


@pytest.mark.parametrize("fog", [False, True], ids=["vacuum", "fog"])
def test_half_opaque_mask_identity_matches_path_through_the_levels(fog):
    """The stylized vertices that sample their opaque part alone (path.opaque_share): the first
    of a walk (path.walk, volume.py's walk in fog) and the source of a first_n_hits bounce. With
    identity the image is Mitsuba's path / volpath image, at two stylized levels, through a
    half-opaque card."""
    from helpers.media import assert_matches_volpath
    d = scene(mask(0.5))
    if fog:
        d["fog"] = {"type": "homogeneous", "sigma_t": {"type": "rgb", "value": [0.1, 0.15, 0.2]},
                    "albedo": {"type": "rgb", "value": [0.8, 0.8, 0.8]}}
        d["sensor"]["medium"] = {"type": "ref", "id": "fog"}
    integ = make_integrator("identity", inner=4, stylize="first_n_hits", stylize_depth=2)
    if fog:
        assert_matches_volpath(mi.load_dict(d), integ)
        return
    # per pixel as well, with 128 spp (x inner 4) per render: this level finds the lamp by BSDF
    # sampling only (docs/guide.md, first_n_hits), about once in 256 bounces from the card, and the
    # t-test needs every render to hold several such samples per pixel (helpers/stats.pixel_t_test).
    # At 4 spp it failed here (max |t| 12 to 14; 28 with a diffuse card) with no bias: |t| fell as
    # the spp grew (test_recursion.py, test_first_n_hits_depth_2_under_a_small_light_per_pixel).
    # Measured at 128 spp, three seed pairs: 4.7..5.4
    ours = renders(d, integ, DEEP_SPP, 100)
    ref = renders(d, mi.load_dict({"type": "path"}), 2 * DEEP_SPP, 900)
    z = mean_z(ours, ref)
    assert np.all(np.abs(z) < Z_MAX), f"image means differ: z = {z}"
    tmax, thr, frac = pixel_t_test(ours, ref, 1e-3)
    assert tmax < thr, f"max |t| {tmax:.2f} over threshold {thr:.2f} ({frac:.4%})"
