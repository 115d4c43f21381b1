"""The walk's hooks in scenes with participating media: feature lines beyond the camera ray and
LLaT's image coordinate (kernel/volume.py carries the same hooks as kernel/path.py).

Each scene is rendered twice, as it is and with the whole scene inside a thin homogeneous medium
(the sensor's medium: no boundary surface). The medium absorbs only (albedo 0), so a camera sample
either crosses it unscattered, with free-flight weight exactly 1 (grey extinction: transmittance
over its own density), or dies at its first collision. A sample survives its flights to a vertex
with probability T = exp(-sigma_t l), l the path length, and every path below crosses the scene's
bounding box on at most two segments, each no longer than the box's diagonal D: T >= T_min = exp(-2
sigma_t D). So the medium scales each sample's expected value by a factor in [T_min, 1]; that, and
the binomial noise of which samples died, bound the difference to the image without the medium.
"""
import math

import numpy as np
import pytest
from tone.scenes import HATCH, first_hit_mask, mirror_scene

import styletrace  # noqa: F401
from styletrace.frontends.api import make_integrator, passes
from styletrace.gate import mi

T = mi.ScalarTransform4f
BLACK = {"type": "diffuse", "reflectance": {"type": "rgb", "value": [0.0, 0.0, 0.0]}}
SIGMA_T = 0.002
#: z of the one-sided bounds below (a false failure about once in 30 000 runs)
Z = 4.0


def thin_medium() -> dict:
    return {"type": "homogeneous", "albedo": 0.0, "sigma_t": SIGMA_T}


def t_min(scene: mi.Scene) -> float:
    """The lowest transmittance of a path of two segments inside the box of the scene and its
    camera."""
    box = scene.bbox()
    eye = np.asarray(scene.sensors()[0].world_transform() @ mi.ScalarPoint3f(0.0))
    lo, hi = np.minimum(np.asarray(box.min), eye), np.maximum(np.asarray(box.max), eye)
    return math.exp(-2.0 * SIGMA_T * float(np.linalg.norm(hi - lo)))


def image(scene, spp, seed=5, **values) -> np.ndarray:
    *_, last = passes(scene, make_integrator(**values), spp, seed=seed)
    return np.asarray(last.image, dtype=np.float64)[..., :3]


# ---- feature lines on the edge past a mirror -----------------------------------------------------
def camera(res):
    return {"type": "perspective", "fov": 40.0, "fov_axis": "smaller",
            "to_world": T().look_at(origin=[0, 0, 0], target=[0, 0, -1], up=[0, 1, 0]),
            "sampler": {"type": "independent"},
            "film": {"type": "hdrfilm", "width": res, "height": res, "rfilter": {"type": "box"}}}


def reflected_sphere(res: int, medium: bool) -> mi.Scene:
    """A mirror tilted 45 degrees fills the view and shows a black sphere beside it
    (tests/kernel/ test_lines.py's scene): every line is found on edge 1, past the mirror, none
    on the camera ray."""
    sensor = camera(res)
    if medium:
        sensor["medium"] = thin_medium()
    return mi.load_dict(
        {
            "type": "scene",
            "sensor": sensor,
            "mirror": {
                "type": "rectangle",
                "bsdf": {"type": "conductor", "material": "none"},
                "to_world": T().translate([0, 0, -5])
                @ T().rotate([0, 1, 0], 45.0)
                @ T().scale(8.0),
            },
            "sphere": {"type": "sphere", "center": [3, 0, -5], "radius": 1.0, "bsdf": BLACK},
        }
    )


@pytest.mark.parametrize(
    "mode",
    [
        {},
        {"stylize": "first_n_hits", "stylize_depth": 2, "inner_samples": "1,1"},
        {"stylize": "first_object_hit"},
    ],
    ids=["first_hit", "first_n_hits", "first_object_hit"],
)
def test_lines_past_a_mirror_are_drawn_in_a_thin_medium(mode):
    """White lines on a black, unlit scene: each camera sample is 1 where a line fired, else 0, so
    the image's sum times spp counts the samples that drew a line, S (a sum of Bernoulli variables,
    variance at most its mean). Without the medium its mean is S0; in the medium each sample's
    chance is scaled by its transmittance to the line's edge, so E[S_med] lies in
    [T_min E[S0], E[S0]]. With both counts' variance bounded by their sum V = S_med + S0:
    S0 - S_med >= -Z sqrt(V)  and  T_min S0 - S_med <= Z sqrt(V). Lines absent in the medium (the
    walk dropping its hook) give S_med = 0."""
    res, spp = 64, 32
    values = {
        "style": "identity",
        "inner_samples": 1,
        "lines": True,
        "line_color": "1,1,1",
        "line_depth": 2,
        **mode,
    }
    plain = image(reflected_sphere(res, False), spp, **values)
    scene = reflected_sphere(res, True)
    foggy = image(scene, spp, **values)
    s0, s_med = plain[..., 0].sum() * spp, foggy[..., 0].sum() * spp
    spread = Z * math.sqrt(s0 + s_med)
    assert s0 > 2000                               # the mirrored outline: ~2 px wide, ~70 px long
    assert s0 - s_med >= -spread, (s0, s_med)
    assert t_min(scene) * s0 - s_med <= spread, (s0, s_med, t_min(scene))


# ---- LLaT hatching seen in a mirror --------------------------------------------------------------
@pytest.mark.parametrize(
    "mode",
    [
        {"stylize": "first_object_hit"},
        {"stylize": "first_n_hits", "stylize_depth": 2, "inner_samples": "1,1"},
    ],
    ids=["first_object_hit", "first_n_hits"],
)
def test_hatching_in_a_mirror_keeps_its_image_coordinate_in_a_thin_medium(mode):
    """Hatched planes seen directly and in a flat mirror (tests/tone/scenes.py), unlit: a
    sample's value is the hatching's colour at its image coordinate, which LLaT's lifting takes
    from the camera ray alone here (pinhole, all-delta prefix: the first-edge pixel). The camera
    rays are the same in both renders, so each sample in the medium is its value without the
    medium (survived) or 0 (died, probability at most q = 1 - T_min): per pixel the medium image
    is at most the plain one, and over the N samples of the mirror the mean difference is at most
    g_max (q + Z sqrt(q / N)), g_max the brighter of the hatching's two colours. A coordinate
    lost in the medium (the position's projection instead) puts the lines elsewhere: about half
    the mirror's pixels then differ by g_max."""
    spp = 4
    values = {"style": "identity", "inner_samples": 1, **mode}
    plain_scene = mirror_scene(dict(HATCH))
    scene = mirror_scene(dict(HATCH), sensor_extra={"medium": thin_medium()})
    plain, foggy = image(plain_scene, spp, **values), image(scene, spp, **values)
    seen = first_hit_mask(scene, "reflector") & (plain.mean(axis=2) > 0.01)
    assert seen.sum() > 300
    g_max, q, n = 0.97, 1.0 - t_min(scene), seen.sum() * spp
    diff = (plain - foggy)[seen]
    assert diff.min() >= -1e-5, diff.min()          # no sample gains in the medium
    assert diff.mean() <= g_max * (q + Z * math.sqrt(q / n)), (diff.mean(), q, n)
