"""Participating media: with the identity style `stylized` equals Mitsuba's `volpath`
(kernel/volume.py)."""
import numpy as np
import pytest
from helpers.media import (
    INNER,
    SCENES,
    SPP,
    Z_MAX,
    assert_matches_volpath,
    fog_ball,
    foggy_room,
    renders,
)
from helpers.stats import mean_z

import styletrace  # noqa: F401
from styletrace.frontends.api import make_integrator
from styletrace.gate import mi


@pytest.mark.parametrize("name", list(SCENES))
def test_identity_matches_volpath(name):
    assert_matches_volpath(mi.load_dict(SCENES[name]()), make_integrator("identity", inner=INNER))


def test_the_comparison_detects_media_ignored():
    """Mitsuba's `path` (which ignores media) against volpath, by the same test: far apart (the
    issue's z = 58)."""
    scene = mi.load_dict(fog_ball())
    ours = renders(scene, mi.load_dict({"type": "path"}), SPP * INNER, 1000)
    ref = renders(scene, mi.load_dict({"type": "volpath"}), SPP * INNER, 5000)
    assert np.any(np.abs(mean_z(ours, ref)) > Z_MAX)


def test_the_media_switch_is_off_without_media():
    """Scenes without media trace the plain path kernel (path.walk), those with media the
    volumetric one."""
    plain = fog_ball()
    del plain["ball"]["interior"]
    for d, media in ((plain, False), (fog_ball(), True), (foggy_room(), True)):
        from styletrace.kernel.render_context import RenderContext
        integrator = make_integrator("identity")
        with RenderContext(integrator, mi.load_dict(d)):
            assert integrator.media is media
