"""The wild-estimate warning on real renders: the gamma series on the Cornell box (a small bright
light) is wild, direct application and the furnace (no fireflies: every child equals the exitant
radiance) are not. 32x32, 4 spp, fixed seeds."""
from styletrace import wild
from styletrace.frontends import api


def render(scene, estimator):
    integ = api.make_integrator("gamma", inner=16, estimator=estimator)
    img = api.render(scene, integrator=integ, spp=4, width=32, height=32, seed=0)
    return img, integ.settings


def test_gamma_series_on_cornell_box_is_reported():
    img, settings = render("cornell-box", "series")
    frac, lo, hi, med = wild.measure(img, 0.0, None)
    # measured: 0.68% of values, min -23.6, median 0.23
    assert frac >= wild.WILD_FRACTION and lo < -10 * med
    msg = wild.warning(img, settings)
    assert msg is not None and "'series'" in msg and "gamma" in msg and "\n" not in msg
    assert "--expansion-pass 64" in msg  # the pass is off: the warning names it


def test_tame_renders_are_not_reported():
    for scene, estimator in (("cornell-box", "direct"), ("furnace", "series")):
        img, settings = render(scene, estimator)
        assert wild.warning(img, settings) is None, (scene, estimator)
