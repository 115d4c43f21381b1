"""Per-object styles: PBR objects stay PBR, styled objects are stylized, also in mirrors."""
import numpy as np
import pytest
from helpers.stats import mean_threshold, mean_z, pixel_t_test

import styletrace  # noqa: F401
from styletrace.frontends.api import make_integrator, passes
from styletrace.gate import mi

T = mi.ScalarTransform4f
RES = 32
GREY = {"type": "diffuse", "reflectance": {"type": "rgb", "value": [0.5, 0.5, 0.5]}}


def mirror_scene(hidden="styled"):
    """A perfect mirror behind the scene reflects a grey sphere (albedo 0.5) that sits behind the
    camera, so the camera sees it only in the mirror; a second grey sphere, always PBR, is seen
    directly (and in the mirror). White sky E = 1, so both spheres have exitant radiance exactly
    0.5. `hidden`: 'styled' (cel, levels 0.2/0.9), 'plain' (PBR) or None (absent)."""
    d = {
        "type": "scene",
        "sensor": {
            "type": "perspective",
            "fov": 40,
            "to_world": T().look_at(origin=[0, 0, 4], target=[0, 0, 0], up=[0, 1, 0]),
            "sampler": {"type": "independent"},
            "film": {"type": "hdrfilm", "width": RES, "height": RES, "rfilter": {"type": "box"}},
        },
        "mirror": {
            "type": "rectangle",
            "to_world": T().translate([0, 0, -2]) @ T().scale(20),
            "bsdf": {"type": "conductor", "material": "none"},
        },
        "visible": {"type": "sphere", "center": [-1.0, 0, 0], "radius": 0.5, "bsdf": GREY},
        "sky": {"type": "constant", "radiance": {"type": "rgb", "value": [1, 1, 1]}},
    }
    if hidden:
        bsdf = (
            {
                "type": "styled",
                "style": "cel",
                "levels": "0.2,0.9",
                "inner_samples": 16,
                "bsdf": GREY,
            }
            if hidden == "styled"
            else GREY
        )
        d["hidden"] = {"type": "sphere", "center": [1.6, 0, 6.2], "radius": 1.6, "bsdf": bsdf}
    return mi.load_dict(d)


def render(scene, integrator, spp, seed):
    *_, last = passes(scene, integrator, spp, seed=seed)
    return last.image.astype(np.float64)


@pytest.fixture(scope="module")
def reflection():
    """Pixels whose every camera sample sees the hidden sphere in the mirror (found with `path`)."""
    path = mi.load_dict({"type": "path"})
    a = render(mirror_scene("plain"), path, 64, 1)
    b = render(mirror_scene(None), path, 64, 1)
    seen = np.abs(a - b).mean(axis=2) > 0.25
    core = seen.copy()  # drop the silhouette: its pixels mix sphere and sky
    core[1:] &= seen[:-1]
    core[:-1] &= seen[1:]
    core[:, 1:] &= seen[:, :-1]
    core[:, :-1] &= seen[:, 1:]
    grown = seen.copy()
    grown[1:] |= seen[:-1]
    grown[:-1] |= seen[1:]
    grown[:, 1:] |= seen[:, :-1]
    grown[:, :-1] |= seen[:, 1:]
    assert core.sum() >= 20
    return core, grown


def test_styled_object_in_a_mirror_is_stylized(reflection):
    core, _ = reflection
    img = render(
        mirror_scene("styled"), make_integrator("identity", stylize="first_object_hit"), 4, 2
    )
    # I = 0.5 (grey albedo 0.5 under a white sky) < 0.75, so cel outputs exactly grey 0.2
    np.testing.assert_allclose(img[core], 0.2, atol=1e-5)


def test_camera_depth_first_hit_leaves_reflections_pbr(reflection):
    core, _ = reflection
    img = render(mirror_scene("styled"), make_integrator("identity", stylize="first_hit"), 4, 3)
    # the first hit is the PBR mirror, so the reflection keeps the sphere's physical radiance,
    # exactly 0.5 in expectation: a z-test over the (independent) reflection pixels, and no pixel at
    # the cel level 0.2
    assert not np.isclose(img[core], 0.2, atol=1e-3).all(axis=1).any()
    vals = img[core]
    z = (vals.mean(0) - 0.5) / (vals.std(0, ddof=1) / np.sqrt(len(vals)))
    assert np.all(np.abs(z) < 4), f"reflection mean {vals.mean(0)} vs 0.5: z = {z}"


def test_pbr_objects_match_mitsuba_path(reflection):
    """Every pixel of the first_object_hit render that does not see the styled sphere matches
    `path`."""
    _, grown = reflection
    k = 12
    styled, plain = mirror_scene("styled"), mirror_scene("plain")
    integ = make_integrator("identity", stylize="first_object_hit")
    ours = np.stack([render(styled, integ, 8, 100 + i) for i in range(k)])
    ref = np.stack([render(plain, mi.load_dict({"type": "path"}), 8, 500 + i) for i in range(k)])
    keep = ~grown
    a, b = ours[:, keep][:, :, None, :], ref[:, keep][:, :, None, :]
    assert np.all(np.abs(mean_z(a, b)) < mean_threshold(k))
    tmax, thr, _ = pixel_t_test(a, b)
    assert tmax < thr
