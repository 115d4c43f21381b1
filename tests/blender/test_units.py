"""The light-unit conversions of `styletrace.blender.units`, checked against Cycles one light at a
time.

A white diffuse plane seen straight down by an orthographic camera, lit by one light 2 m above it:
the centre of the image has radiance E / pi, E the irradiance there. Cycles and styletrace must
agree within 1.5% (both estimates have well under 0.5% noise at these counts); the docstring of
`units` derives the factors.
"""
import math
import os

import pytest
import scenes as S

LIGHTS = {
    "point": ("POINT", dict(energy=10.0, shadow_soft_size=0.0)),
    "spot": (
        "SPOT",
        dict(energy=10.0, shadow_soft_size=0.0, spot_size=math.radians(60), spot_blend=0.0),
    ),
    "sun": ("SUN", dict(energy=2.0, angle=0.0)),
    "square": ("AREA", dict(energy=10.0, size=0.3)),
    "rectangle": ("AREA", dict(energy=10.0, shape="RECTANGLE", size=0.4, size_y=0.1)),
    "disk": ("AREA", dict(energy=10.0, shape="DISK", size=0.3)),
    "world": (
        "WORLD",
        dict(color=(0.3, 0.4, 0.5), strength=2.0),
    ),  # background colour x strength is radiance
}


def scene(kind, values):
    s = S.reset(16)
    white, _ = S.material("white", Color=(1.0, 1.0, 1.0))
    S.plane(50, mat=white)
    # below the light: styletrace sees its back
    S.camera((0, 0, 1), (0, 0, 0), type="ORTHO", ortho_scale=0.2)
    if kind == "WORLD":
        bg = s.world.node_tree.nodes["Background"]
        bg.inputs["Color"].default_value = (*values["color"], 1.0)
        bg.inputs["Strength"].default_value = values["strength"]
    else:
        S.light(kind, (0, 0, 2), **values)
    return s


@pytest.mark.parametrize("name", sorted(LIGHTS))
def test_light_units_match_cycles(name, tmp_path):
    kind, values = LIGHTS[name]
    scene(kind, values)
    cycles = S.cycles(os.path.join(tmp_path, "c.exr"), 256)[4:12, 4:12].mean()
    st = S.styletrace(os.path.join(tmp_path, "s.exr"), 256, pass_spp=256, style="identity")[
        "Combined"
    ]
    st = st[4:12, 4:12, :3].mean()
    # the irradiance the conversion was derived for, at the centre (cosines ~1 over the 0.2 m field)
    analytic = {"point": 10 / (4 * math.pi) / 4, "spot": 10 / (4 * math.pi) / 4, "sun": 2.0,
                # the world: E = pi L on an unoccluded plane
                "world": math.pi * 2.0 * 0.4}.get(name)
    print(
        f"{name}: Cycles {cycles:.5f}, styletrace {st:.5f}, analytic "
        f"{analytic and analytic / math.pi}"
    )
    assert abs(st / cycles - 1) < 0.015, (name, cycles, st)
    if analytic is not None:
        assert abs(cycles / (analytic / math.pi) - 1) < 0.01


@pytest.mark.parametrize("blend", [0.3, 0.8])
def test_spot_blend_matches_cycles(blend, tmp_path):
    """A 60-degree spot with a soft edge, its whole cone in view: the light reaching the plane
    (the image mean) within 1.5%. Mitsuba's linear ramp differs in shape from Cycles' smoothstep,
    not in power (`lights.spot_beam`); a ramp that starts where the smoothstep reaches 1 was 8%
    short at blend 0.8."""
    S.reset(32)
    white, _ = S.material("white", Color=(1.0, 1.0, 1.0))
    S.plane(50, mat=white)
    S.camera((0, 0, 1), (0, 0, 0), type="ORTHO", ortho_scale=3.0)
    S.light(
        "SPOT",
        (0, 0, 2),
        energy=10.0,
        shadow_soft_size=0.0,
        spot_size=math.radians(60),
        spot_blend=blend,
    )
    cycles = S.cycles(os.path.join(tmp_path, "c.exr"), 64).mean()
    st = S.styletrace(os.path.join(tmp_path, "s.exr"), 64, pass_spp=64, style="identity")[
        "Combined"
    ][..., :3].mean()
    print(f"spot blend {blend}: Cycles {cycles:.5f}, styletrace {st:.5f}")
    assert abs(st / cycles - 1) < 0.015
