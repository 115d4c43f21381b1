"""Cel band boundaries on a smooth gradient lie within 1 pixel of the reference's when the
expectation is denoised, and not when it is not (so the test can tell).

The scene: a large diffuse plane facing the camera, lit at a grazing angle by a small area light
near its left edge: the expected radiance falls smoothly across the image, and next-event estimation
of the area light gives each child real noise. Reference: direct application with REF children per
camera sample, the same seed (the same camera rays). Band of a pixel: the index of its value among
the cel levels (every camera sample of a pixel on one side of a threshold gives exactly a level). A
pixel whose band differs from the reference's passes when it is within Chebyshev distance 1 of a
reference boundary pixel (one with an 8-neighbour in another band): the boundary moved by at most
one pixel. REF = 4096: the reference's own flips are then confined to pixels whose expectation lies
within about 4 / sqrt(4096) of the children's relative spread of a threshold, i.e. on the boundary
itself.
"""
import numpy as np

import styletrace
from styletrace.frontends import api
from styletrace.gate import mi

RES, N, REF = 48, 4, 4096
LEVELS = (0.1, 0.4, 0.7, 1.0)


def gradient_scene():
    T = mi.ScalarTransform4f
    return api.load_scene(
        {
            "type": "scene",
            "sensor": {
                "type": "perspective",
                "fov": 40,
                "to_world": T().look_at(origin=[0, 0, 5], target=[0, 0, 0], up=[0, 1, 0]),
                "film": {
                    "type": "hdrfilm",
                    "width": RES,
                    "height": RES,
                    "rfilter": {"type": "box"},
                },
                "sampler": {"type": "independent", "sample_count": 1},
            },
            "plane": {
                "type": "rectangle",
                "to_world": T().scale(4),
                "bsdf": {
                    "type": "diffuse",
                    "reflectance": {"type": "rgb", "value": [0.7, 0.7, 0.7]},
                },
            },
            "light": {
                "type": "rectangle",
                "to_world": T().translate([-2.2, 0, 0.6]).rotate([0, 1, 0], 80).scale(0.5),
                "emitter": {"type": "area", "radiance": {"type": "rgb", "value": [6, 6, 6]}},
            },
        }
    )


def bands(img):
    lum = np.asarray(img, dtype=np.float64)[..., 1]
    return np.abs(lum[..., None] - np.asarray(LEVELS)).argmin(-1)


def far_mismatches(ref, test):
    b = bands(ref)
    edge = np.zeros_like(b, dtype=bool)
    for dy in (-1, 0, 1):
        for dx in (-1, 0, 1):
            sh = np.roll(np.roll(b, dy, 0), dx, 1)
            edge |= sh != b
    edge[0, :] = edge[-1, :] = edge[:, 0] = edge[:, -1] = False  # np.roll wraps around the image
    near = edge.copy()
    for dy in (-1, 0, 1):
        for dx in (-1, 0, 1):
            near |= np.roll(np.roll(edge, dy, 0), dx, 1)
    return int(((bands(test) != b) & ~near).sum()), int(edge.sum())


def test_cel_boundaries_within_one_pixel():
    scene = gradient_scene()
    kw = dict(
        style="cel", spp=1, seed=5, thresholds="0.05,0.1,0.2", levels=",".join(map(str, LEVELS))
    )
    ref = api.render(scene, inner=REF, **kw)
    denoised = styletrace.render(scene, inner=N, denoise="expectation", **kw)
    noisy = api.render(scene, inner=N, **kw)
    far, edges = far_mismatches(ref, denoised)
    assert edges > RES, "the reference has too few band boundaries for the test to mean anything"
    assert far == 0, f"{far} pixels change band more than 1 pixel from the reference's boundaries"
    assert far_mismatches(ref, noisy)[0] >= 5, (
        "without denoising the bands should flip away from the boundaries"
    )
