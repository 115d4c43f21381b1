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

Each comparison is repeated with one conversion broken on purpose (monkeypatched), and must then
fail.
"""
import os

import numpy as np
import pytest
import scenes as S

from styletrace.blender import units

SIZE, CYCLES_SPP, STYLETRACE_SPP = 64, 512, 128
Z = 3.89
DIFFUSE = ("room", "textured_plane", "instanced")
GLOSSY = ("glossy", "glass")

#: one deliberate mistake per comparison, each a plausible error in a conversion
BROKEN = {
    # the pi of a cosine lobe forgotten
    "room": ("area_radiance", lambda power, area: power / area),
    # Blender's v kept as Mitsuba's
    "textured_plane": ("flip_v", lambda v: v),
    # the sun's strength taken as radiance
    "instanced": ("sun_irradiance", lambda strength: strength / np.pi),
    # watts taken as pi times too large
    "glossy": ("point_intensity", lambda power: power / (4 * np.pi * np.pi)),
    "glass": ("point_intensity", lambda power: power / (4 * np.pi * np.pi)),
}


def compare(name, tmp_path):
    """(mean ratios per channel, fraction of blocks with |z| < Z, max |z|) of styletrace against
    Cycles."""
    ref, ref_var = S.cycles_reference(name, CYCLES_SPP)
    S.SCENES[name](SIZE)
    out = S.styletrace(
        os.path.join(tmp_path, f"{name}.exr"),
        STYLETRACE_SPP,
        seed=7,
        pass_spp=STYLETRACE_SPP,
        style="identity",
        aovs=True,
    )
    img, var = out["Combined"][..., :3], out["Variance"]
    z = S.block_z(img, var, ref, ref_var)
    ratio = img.mean(axis=(0, 1)) / ref.mean(axis=(0, 1))
    print(
        f"{name}: cycles mean {ref.mean(axis=(0, 1))}, styletrace {img.mean(axis=(0, 1))}, ratio "
        f"{ratio}, "
        f"blocks passing {np.mean(np.abs(z) < Z):.3f}, max |z| {np.abs(z).max():.2f}"
    )
    return ratio, float(np.mean(np.abs(z) < Z)), float(np.abs(z).max())


def passes(name, ratio, rate) -> bool:
    if name in DIFFUSE:
        return bool(np.all(np.abs(ratio - 1) < 0.02) and rate >= 0.99)
    return bool(np.all(np.abs(ratio - 1) < 0.05))


@pytest.mark.parametrize("name", DIFFUSE + GLOSSY)
def test_matches_cycles(name, tmp_path):
    ratio, rate, _ = compare(name, tmp_path)
    assert passes(name, ratio, rate), (name, ratio, rate)


@pytest.mark.parametrize("name", DIFFUSE + GLOSSY)
def test_broken_conversion_fails(name, tmp_path, monkeypatch):
    attr, broken = BROKEN[name]
    monkeypatch.setattr(units, attr, broken)
    ratio, rate, _ = compare(name, tmp_path)
    assert not passes(name, ratio, rate), (
        f"{name} still matches Cycles with units.{attr} broken: {ratio}, {rate}"
    )
