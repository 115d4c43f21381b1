"""`line_mode lifted` in the `stylized` integrator (kernel/line_hooks.py `lifted`): the camera
sample's film point and lens sample are recovered exactly; the integrator draws the lines of the
standalone renderer (kernel/lifted_lines.Lifted, tested against image-space references in
test_lifted_lines_render.py) with the priority of Eq. 34 and traces no children where a type
fired; through a glass slab the auxiliary paths refract and the lines keep their coverage."""
import numpy as np
import pytest
from helpers.line_scenes import ball_mask, line_scene, reference

import styletrace
from styletrace.config.line_types import LineType
from styletrace.errors import SceneError
from styletrace.frontends import api
from styletrace.gate import mi
from styletrace.kernel.lifted_lines import Lifted

styletrace.init()

T = mi.ScalarTransform4f
RED = LineType("shape_id", 0.5, "disk", 1.5, 8, (1.0, 0.0, 0.0), 0)
BLUE = LineType("depth", 0.08, "disk", 2.5, 8, (0.0, 0.0, 1.0), 1)
TYPES = (
    "shape_id radius=1.5 count=8 color=1,0,0; depth threshold=0.08 radius=2.5 count=8 color=0,0,1"
)


@pytest.mark.parametrize(
    "lens",
    [{"type": "perspective"}, {"type": "thinlens", "aperture_radius": 0.3, "focus_distance": 6.0}],
    ids=["pinhole", "thinlens"],
)
def test_conditioning_gives_the_camera_ray_back(lens):
    """For 1000 random film positions and lens samples, the (s, aperture) recovered from
    Mitsuba's camera ray traces that ray again (origin and direction to float precision)."""
    sc = mi.load_dict(
        {
            "type": "scene",
            "r": {"type": "rectangle"},
            "sensor": {
                **lens,
                "fov": 40,
                "film": {"type": "hdrfilm", "width": 40, "height": 30},
                "to_world": T().look_at(origin=[0.3, 0.2, 6], target=[0, 0, 0], up=[0, 1, 0]),
            },
        }
    )
    lifted = Lifted(sc, [RED])
    rng = np.random.default_rng(0)
    uv, ap = (mi.Point2f(*rng.random((2, 1000)).astype(np.float32)) for _ in range(2))
    ray, _ = sc.sensors()[0].sample_ray(mi.Float(0.0), mi.Float(0.5), uv, ap)
    s, a = lifted.conditioning(mi.Ray3f(ray))
    back = lifted._ray(s, mi.Bool(True), a)
    assert np.abs(np.array(back.o) - np.array(ray.o)).max() < 1e-5
    assert np.abs(np.array(back.d) - np.array(ray.d)).max() < 1e-5


def shares(img):
    """(red share, blue share) of the camera samples per pixel: lit by a grey sky, the grey scene
    gives L with r = g = b, so red minus green is the share drawn in the red type's colour, blue
    minus green the blue type's."""
    return img[..., 0] - img[..., 1], img[..., 2] - img[..., 1]


def test_the_integrator_draws_the_standalone_lines_with_priority():
    """Two overlapping types (shape ids red, priority 0; depth slope blue, priority 1),
    line_depth 2, on the box and the mirror ball: the integrator's shares of red and blue samples
    equal the standalone renderer's (its own random numbers) within 4 standard errors of the two
    image means (Bernoulli samples)."""
    spp = 32
    img = styletrace.render(
        line_scene(light=0.5),
        style="identity",
        inner=1,
        spp=spp,
        seed=3,
        lines=True,
        line_mode="lifted",
        line_depth=2,
        line_types=TYPES,
    )
    red, blue = shares(np.asarray(img, np.float64))
    ref = Lifted(mi.load_dict(line_scene()), [RED, BLUE], depth=2)
    ref.render(spp, seed=4)
    want_red, want_blue = (
        ref.samples[0].mean(axis=2),
        (ref.samples[1] & ~ref.samples[0]).mean(axis=2),
    )
    assert want_red.mean() > 0.03 and want_blue.mean() > 0.01
    for got, want in ((red, want_red), (blue, want_blue)):
        var = (got * (1 - got)).clip(0) / spp + (want * (1 - want)).clip(0) / spp
        se = np.sqrt(var.sum()) / got.size
        assert abs(got.mean() - want.mean()) < 4 * se, (got.mean(), want.mean(), se)


@pytest.mark.parametrize("flat", [False, True], ids=["ball", "flat"])
def test_rendered_lines_in_a_mirror_keep_the_reference_width(flat):
    """A render (line_mode lifted, one shape-id type, line_depth 2): the lines' coverage inside
    the mirror ball, and inside the flat mirror, relative to their coverage on the directly seen
    box, is the image-space reference's (the pair test on the shapes seen along perfectly
    specular paths) within 10%: the lines keep their width in the curved mirror. West's cone
    departs from it by far more on the ball (test_lifted_lines_render.py)."""
    d = line_scene(flat=flat, light=0.5)
    img = styletrace.render(
        d,
        style="identity",
        inner=1,
        spp=16,
        seed=8,
        lines=True,
        line_mode="lifted",
        line_depth=2,
        line_types="shape_id radius=1.5 count=8 color=1,0,0",
    )
    red, _ = shares(np.asarray(img, np.float64))
    sc = mi.load_dict(line_scene(flat=flat))
    ball = ball_mask(sc)
    direct = (np.arange(red.shape[1])[None, :] < red.shape[1] // 2) & ~ball
    ref = reference(sc, RED)

    def ratio(x):
        return x[ball].mean() / x[direct].mean()
    assert ref[ball].mean() > 0.03
    assert abs(ratio(red) / ratio(ref) - 1) < 0.10, (ratio(red), ratio(ref))


def test_no_children_are_traced_where_a_line_type_fired():
    """The error AOVs' children count (per camera sample, averaged per pixel) is 0 in pixels
    whose every sample drew a line, and the full count elsewhere on lit geometry."""
    n = 4
    integ = api.make_integrator(
        "cel",
        inner=n,
        lines=True,
        line_mode="lifted",
        line_depth=2,
        aovs=True,
        line_types="shape_id radius=3 count=16 color=1,0,0",
    )
    *_, last = api.passes(mi.load_dict(line_scene(light=0.5)), integ, 8, seed=2)
    img, aovs = np.asarray(last.image), last.aovs
    children = np.asarray(aovs["children"])
    red, _ = shares(np.asarray(img, np.float64))
    inked = red > 0.999
    assert inked.sum() > 20
    assert np.all(children[inked] == 0)
    plain = red < 1e-6
    assert np.median(children[plain & (children > 0)]) == n


def slab_scene(glass: bool) -> dict:
    """A box seen through a glass slab (IOR 1.5, 0.3 thick) that fills the view, or without the
    slab."""
    d = line_scene(light=0.5)
    del d["ball"], d["back"]
    d["box"]["to_world"] = T().rotate([1, 1, 0], 30) @ T().scale(1.0)
    if glass:
        d["slab"] = {"type": "cube", "bsdf": {"type": "dielectric", "int_ior": 1.5},
                     "to_world": T().translate([0, 0, 3]) @ T().scale([6, 6, 0.15])}
    return d


def test_lines_behind_a_glass_slab_keep_their_coverage():
    """Behind flat glass the auxiliary paths refract with the base path (line_depth 3: the slab's
    two faces, then the box): the box's outline covers the image as it does without the slab,
    within 10% (the slab moves the box's image by a few percent, and Fresnel reflection sends
    about 8% of the base paths back to an empty sky, where no pair fires). Paths that stopped at
    the glass drew no line at all."""
    kw = dict(style="identity", inner=1, spp=16, seed=5, lines=True, line_mode="lifted",
              line_types="shape_id radius=1.5 count=8 color=1,0,0")
    plain, _ = shares(
        np.asarray(styletrace.render(slab_scene(False), line_depth=1, **kw), np.float64)
    )
    seen, _ = shares(
        np.asarray(styletrace.render(slab_scene(True), line_depth=3, **kw), np.float64)
    )
    assert plain.mean() > 0.02
    assert abs(seen.mean() / plain.mean() - 1) < 0.10, (seen.mean(), plain.mean())


def test_line_diffuse_carries_the_pairs_on_through_diffuse_vertices():
    """line_diffuse: at a diffuse base vertex the auxiliary paths turn the base's direction by
    the minimal rotation and go on, so edges in what the grey surfaces see (the box, the ball,
    the sky beyond them) draw lines in their indirect view; without it the pairs stop there. Same
    seed, so the same random numbers: every pair that fired without the switch fires with it (the
    first vertex is tested alike), and more fire with it, sample by sample."""
    kw = dict(
        style="identity",
        inner=1,
        spp=8,
        seed=9,
        lines=True,
        line_mode="lifted",
        line_depth=2,
        line_types="shape_id radius=1.5 count=4 color=1,0,0",
    )
    off, _ = shares(np.asarray(styletrace.render(line_scene(light=0.5), **kw), np.float64))
    on, _ = shares(
        np.asarray(styletrace.render(line_scene(light=0.5), line_diffuse=True, **kw), np.float64)
    )
    assert np.all(on >= off - 1e-6)
    assert (on > off + 1e-6).sum() >= 50, (on > off + 1e-6).sum()


def test_line_objects_keep_the_lines_of_the_named_shapes():
    """line_objects=ball: a pair draws only where one of its hits is on the ball. Same seed, so
    the lines are a subset of those without the list, sample by sample: the ball's rim keeps
    them, the box on the left and the box's reflection inside the ball (hits on the box, not the
    ball) draw none. (The box and the back plane share one BSDF, so Mitsuba merges them into one
    mesh without an id: only the ball can be named here.) An unknown id is refused in one line
    naming the scene's ids."""
    kw = dict(
        style="identity",
        inner=1,
        spp=8,
        seed=4,
        lines=True,
        line_mode="lifted",
        line_depth=2,
        line_types="shape_id radius=1.5 count=8 color=1,0,0",
    )
    every, _ = shares(np.asarray(styletrace.render(line_scene(light=0.5), **kw), np.float64))
    named, _ = shares(
        np.asarray(styletrace.render(line_scene(light=0.5), line_objects="ball", **kw), np.float64)
    )
    # the ball, away from the box
    right = np.arange(every.shape[1]) >= every.shape[1] // 2 + 4
    left = np.arange(every.shape[1]) < every.shape[1] // 2 - 4               # the box
    assert np.all(named <= every + 1e-6)
    assert named[:, right].mean() > 0.01 and named[:, right].mean() < every[:, right].mean()
    assert every[:, left].mean() > 0.02 and named[:, left].max() == 0.0
    with pytest.raises(
        SceneError, match="bad value 'teapot' in 'line_objects': the scene's shape ids are ball"
    ):
        styletrace.render(line_scene(light=0.5), line_objects="teapot", **kw)
