"""`expectation.raster`: a vertex's position on the film, in pixels of the crop window.

D is looked up at each camera sample's own film position (`at_samples`), found by projecting its
vertex through the sensor. Checked against Mitsuba's own placement of the camera samples: every
vertex of a render projects into the pixel the render accumulated it in, on the whole film and on a
crop window (where the projection had been shifted by the crop offset a second time, so that D was
looked up pixels away from the sample).

`Field.at`: a vertex in a pixel that mixes two surfaces takes D from the neighbours that show its
own surface, found by its own albedo (not the pixel's mean albedo, which matches neither surface).
"""
import numpy as np
import pytest

from styletrace.denoise import expectation as X
from styletrace.denoise.probe import Probe
from styletrace.frontends import api
from styletrace.lookdev.record import record
from styletrace.pipeline.passes import Shot

from .test_coverage import plane


@pytest.mark.parametrize("crop", [None, (3, 2, 7, 9)])
def test_a_render_s_vertices_project_into_their_own_pixels(crop):
    scene = plane(crop)
    for _, buf in record(Shot(scene, api.make_integrator(style="cel", inner=1), 4, seed=1)):
        pass
    uv = X.raster(scene, buf.arrays["p"])
    pixel = buf.arrays["pixel"].astype(np.int64)
    assert np.all(np.floor(uv[:, 0]) == pixel % buf.width) and np.all(
        np.floor(uv[:, 1]) == pixel // buf.width
    )


def test_a_vertex_on_a_silhouette_takes_its_own_surface_s_neighbour():
    """`Field.at` in a pixel that mixes two surfaces (here two albedos under different light,
    coplanar so that only the albedo tells them apart): the pixel's D and guide albedo are means
    over both. A vertex of the bright surface must take the pure neighbour of its own surface (E
    = 0.8), not the mixed pixel's D rescaled by the albedo ratio (0.716: 10% off), which it took
    while the neighbours were compared with the pixel's mean albedo."""
    import mitsuba as mi

    from styletrace.kernel.guides import Guides
    a_bright, a_dark = 0.8, 0.1
    # albedo x irradiance: the dark surface is also in shadow
    e_bright, e_dark = a_bright * 1.0, a_dark * 0.05
    d = np.array([[e_bright, (e_bright + e_dark) / 2, e_dark, e_dark]] * 2, np.float32)[
        ..., None
    ].repeat(3, -1)
    albedo = np.array([[a_bright, (a_bright + a_dark) / 2, a_dark, a_dark]] * 2, np.float32)[
        ..., None
    ].repeat(3, -1)
    position = np.zeros((2, 4, 3), np.float32)
    position[..., 0] = np.arange(4, dtype=np.float32) * 0.1
    normal = np.zeros((2, 4, 3), np.float32)
    normal[..., 2] = 1.0
    field = X.Field(d, Guides(albedo, normal, position, normal), 1.0)
    probe = Probe(
        mi.Point2f(1.3, 0.5),
        mi.Point3f(0.13, 0.0, 0.0),
        mi.Vector3f(0.0, 0.0, 1.0),
        mi.UInt32(1),
        mi.Bool(True),
    )
    value = field.at(probe, mi.Color3f(a_bright), mi.Color3f(0.0))
    np.testing.assert_allclose(np.asarray(value).ravel(), [e_bright] * 3, rtol=1e-5)
