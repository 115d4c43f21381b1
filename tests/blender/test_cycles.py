"""styletrace's identity style against Cycles, the reference, on scenes built with bpy.

Cycles renders each scene twice (seeds 1 and 2, 512 samples each, cached under
tests/blender/.cache); the per-pixel variance of their mean is ((a - b) / 2)^2. styletrace renders
through F12 with its error AOVs, whose `Variance` pass is the variance of each pixel's mean. Per 8x8
block of the 64x64 image, z = (difference of the block means) / (standard error of that difference)
(`scenes.block_z`).

Diffuse scenes: the image's mean within 2% per channel and >= 99% of the blocks with |z| < Z (Z =
3.89: a two-sided p of 1e-4, so a correct renderer fails a block of the 64 with probability 0.6%).
Glossy and glass: the mean within 5% (Mitsuba's microfacet models and Cycles' differ in their
multiple-scattering and Fresnel details; the block rates are printed, not asserted).
Principled with Specular IOR Level 0.5 (the interior, lit by sun, sky and lamp): each channel's
image mean within Z standard errors of the ratio of the two means (from styletrace's Variance pass
and the two Cycles renders) plus `PRINCIPLED_MODEL`, the model difference measured on it.

Each comparison is repeated with one conversion broken on purpose (monkeypatched), and must then
fail.
"""
import os

import numpy as np
import pytest
import scenes as S

from styletrace.blender import materials, units

SIZE, CYCLES_SPP, STYLETRACE_SPP = 64, 512, 128
Z = 3.89
DIFFUSE = ("room", "textured_plane", "instanced")
GLOSSY = ("glossy", "glass")
PRINCIPLED = ("interior",)
#: the interior's noise is mostly styletrace's: 512 spp make the standard error of its mean 0.3%
#: (1.2 s); Cycles' two 512-sample renders add 0.2%
PRINCIPLED_SPP = 512
#: the model difference of Principled's dielectric base on the interior (`materials.principled`
#: darkens the diffuse by the specular layer's mean albedo, Cycles by its albedo in the view
#: direction), measured against Cycles at 2 x 2048 samples with styletrace at 4096 spp:
#: 0.9889 0.9910 0.9946 +- 0.0013 0.0013 0.0017; the largest difference, 1.1%, plus 3.89 of its
#: standard errors, rounded up
PRINCIPLED_MODEL = 0.016


def _roughplastic(base, tint, roughness, f0):
    return {"type": "roughplastic", "diffuse_reflectance": base, "int_ior": 1.5,
            "alpha": materials.alpha(roughness), "distribution": "ggx", "nonlinear": True}


#: one deliberate mistake per comparison, each a plausible error in a conversion
BROKEN = {
    # the pi of a cosine lobe forgotten
    "room": (units, "area_radiance", lambda power, area: power / area),
    # Blender's v kept as Mitsuba's
    "textured_plane": (units, "flip_v", lambda v: v),
    # the sun's strength taken as radiance
    "instanced": (units, "sun_irradiance", lambda strength: strength / np.pi),
    # watts taken as pi times too large
    "glossy": (units, "point_intensity", lambda power: power / (4 * np.pi * np.pi)),
    "glass": (units, "point_intensity", lambda power: power / (4 * np.pi * np.pi)),
    # the first mapping of Principled's dielectric base: Mitsuba's roughplastic
    "interior": (materials, "_dielectric", _roughplastic),
}


def compare(name, tmp_path):
    """(mean ratios per channel, fraction of blocks with |z| < Z, max |z|, standard errors of the
    ratios) of styletrace against Cycles."""
    ref, ref_var = S.cycles_reference(name, CYCLES_SPP)
    S.SCENES[name](SIZE)
    spp = PRINCIPLED_SPP if name in PRINCIPLED else STYLETRACE_SPP
    out = S.styletrace(
        os.path.join(tmp_path, f"{name}.exr"),
        spp,
        seed=7,
        pass_spp=spp,
        style="identity",
        aovs=True,
    )
    img, var = out["Combined"][..., :3], out["Variance"]
    z = S.block_z(img, var, ref, ref_var)
    st_mean, cy_mean = img.mean(axis=(0, 1)), ref.mean(axis=(0, 1))
    ratio = st_mean / cy_mean
    # the pixels are independent estimates: the variance of an image mean is the sum of its
    # pixels' variances over the pixel count squared; relative errors add in quadrature
    n = img.shape[0] * img.shape[1]
    se = ratio * np.sqrt(
        var.sum(axis=(0, 1)) / (n * st_mean) ** 2 + ref_var.sum(axis=(0, 1)) / (n * cy_mean) ** 2
    )
    print(
        f"{name}: cycles mean {cy_mean}, styletrace {st_mean}, ratio {ratio} +- {se}, "
        f"blocks passing {np.mean(np.abs(z) < Z):.3f}, max |z| {np.abs(z).max():.2f}"
    )
    return ratio, float(np.mean(np.abs(z) < Z)), float(np.abs(z).max()), se


def passes(name, ratio, rate, se) -> bool:
    if name in DIFFUSE:
        return bool(np.all(np.abs(ratio - 1) < 0.02) and rate >= 0.99)
    if name in PRINCIPLED:
        return bool(np.all(np.abs(ratio - 1) < Z * se + PRINCIPLED_MODEL))
    return bool(np.all(np.abs(ratio - 1) < 0.05))


@pytest.mark.parametrize("name", DIFFUSE + GLOSSY + PRINCIPLED)
def test_matches_cycles(name, tmp_path):
    ratio, rate, _, se = compare(name, tmp_path)
    assert passes(name, ratio, rate, se), (name, ratio, rate, se)


@pytest.mark.parametrize("name", DIFFUSE + GLOSSY + PRINCIPLED)
def test_broken_conversion_fails(name, tmp_path, monkeypatch):
    module, attr, broken = BROKEN[name]
    monkeypatch.setattr(module, attr, broken)
    ratio, rate, _, se = compare(name, tmp_path)
    assert not passes(name, ratio, rate, se), (
        f"{name} still matches Cycles with {module.__name__}.{attr} broken: {ratio}, {rate}"
    )
