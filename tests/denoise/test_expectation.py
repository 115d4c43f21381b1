"""`expectation.raster`: a vertex's position on the film, in pixels of the crop window.

D is looked up at each camera sample's own film position (`at_samples`), found by projecting its vertex through
the sensor. Checked against Mitsuba's own placement of the camera samples: every vertex of a render projects into
the pixel the render accumulated it in, on the whole film and on a crop window (where the projection had been
shifted by the crop offset a second time, so that D was looked up pixels away from the sample).
"""
import numpy as np
import pytest

from styletrace import api
from styletrace.denoise import expectation as X
from styletrace.lookdev.record import record

from .test_coverage import plane


@pytest.mark.parametrize("crop", [None, (3, 2, 7, 9)])
def test_a_render_s_vertices_project_into_their_own_pixels(crop):
    scene = plane(crop)
    for _, buf in record(scene, api.make_integrator(style="cel", inner=1), 4, seed=1):
        pass
    uv = X.raster(scene, buf.arrays["p"])
    pixel = buf.arrays["pixel"].astype(np.int64)
    assert np.all(np.floor(uv[:, 0]) == pixel % buf.width) and np.all(np.floor(uv[:, 1]) == pixel // buf.width)
