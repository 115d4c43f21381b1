"""The guides see through mirrors (`kernel.guides.through_delta`): at a mirror's pixels the albedo
guide is the albedo of the surface the mirror shows, and the normal guide that surface's normal.

Truth from Mitsuba's own `aov` integrator: a camera looks straight at a mirror that fills its
view, and the checkerboard wall behind the camera is what the mirror shows. The same wall seen by
the camera's mirror image (the camera reflected in the mirror's plane, no mirror in the scene) is
the same picture flipped left to right, and Mitsuba's `albedo` AOV of that picture is the truth.
Pixels on a checker edge are left out (the two renders' sub-pixel samples differ there)."""
import numpy as np

from styletrace.frontends import api
from styletrace.gate import mi
from styletrace.kernel import guides

RES = 32
WALL = {
    "type": "rectangle",
    "to_world": mi.ScalarTransform4f().translate([0, 0, 6]).rotate([0, 1, 0], 180).scale(8),
    "bsdf": {
        "type": "diffuse",
        "reflectance": {
            "type": "checkerboard",
            "color0": {"type": "rgb", "value": [0.1, 0.2, 0.3]},
            "color1": {"type": "rgb", "value": [0.8, 0.7, 0.5]},
            "to_uv": mi.ScalarTransform4f().rotate([0, 0, 1], 20).scale([3, 3, 1]),
        },
    },
}


def camera(z, target_z):
    return {
        "type": "perspective",
        "fov": 30,
        "to_world": mi.ScalarTransform4f().look_at(
            origin=[0, 0, z], target=[0, 0, target_z], up=[0, 1, 0]
        ),
        "film": {"type": "hdrfilm", "width": RES, "height": RES, "rfilter": {"type": "box"}},
        "sampler": {"type": "independent", "sample_count": 16},
    }


def test_mirror_pixels_show_the_reflected_surfaces_albedo_and_normal():
    sc = api.load_scene(
        {
            "type": "scene",
            "sensor": camera(4, 0),
            "wall": WALL,
            "mirror": {
                "type": "rectangle",
                "to_world": mi.ScalarTransform4f().scale(20),
                "bsdf": {"type": "conductor"},
            },
        }
    )
    got = guides.first_hit(sc, 16, 3)
    virtual = mi.load_dict({"type": "scene", "sensor": camera(-4, 1), "wall": WALL})
    aov = mi.load_dict({"type": "aov", "aovs": "albedo:albedo"})
    truth = np.asarray(mi.render(virtual, integrator=aov, spp=64, seed=1))[..., -3:][:, ::-1]
    flat = np.ones(truth.shape[:2], bool)  # no checker edge within the pixel's 3 x 3 neighbourhood
    for dy in (-1, 0, 1):
        for dx in (-1, 0, 1):
            flat &= np.abs(np.roll(np.roll(truth, dy, 0), dx, 1) - truth).max(-1) < 1e-6
    flat[[0, -1], :] = flat[:, [0, -1]] = False
    assert flat.sum() > 0.3 * RES * RES, "too few flat pixels: the test would test nothing"
    np.testing.assert_allclose(got.albedo[flat], truth[flat], atol=1e-4)
    # both checker colours are seen
    assert np.unique(np.round(got.albedo[flat], 3), axis=0).shape[0] == 2
    # the wall faces the mirror (-z); the first hit is the mirror itself (+z)
    np.testing.assert_allclose(got.normal.reshape(-1, 3), [[0, 0, -1]] * RES * RES, atol=1e-5)
    np.testing.assert_allclose(
        got.surface_normal.reshape(-1, 3), [[0, 0, 1]] * RES * RES, atol=1e-5
    )
    assert np.allclose(got.position[..., 2], 0.0, atol=1e-5)


def test_a_mirror_that_sees_nothing_keeps_its_specular_weight():
    """No surface behind the chain: the albedo guide is the mirror's reflectance (1 for the
    default conductor, 0.5 for a half-tinted one), not 0 (OIDN's 'nothing to keep') nor the
    diffuse 0 of Mitsuba's AOV."""
    tinted = {
        "type": "conductor",
        "specular_reflectance": {"type": "rgb", "value": [0.5, 0.5, 0.5]},
    }
    for bsdf, want in (({"type": "conductor"}, 1.0), (tinted, 0.5)):
        sc = api.load_scene(
            {
                "type": "scene",
                "sensor": camera(4, 0),
                "mirror": {
                    "type": "rectangle",
                    "to_world": mi.ScalarTransform4f().scale(20),
                    "bsdf": bsdf,
                },
            }
        )
        got = guides.first_hit(sc, 1, 0)
        np.testing.assert_allclose(got.albedo, want, rtol=1e-5)


def wall_scene(rfilter):
    sensor = camera(-4, 1)
    sensor["film"] = dict(sensor["film"], rfilter={"type": rfilter})
    return api.load_scene({"type": "scene", "sensor": sensor, "wall": WALL})


def test_many_samples_are_split_over_launches_of_bounded_size_and_averaged(monkeypatch):
    """A sample count whose rays would not fit one launch (a scene file's 4096 spp at 256 px is
    200 million rays, over 20 GB) is traced in launches of at most `lanes_per_launch` rays, and
    the guides are their mean weighted by each launch's samples: the same as tracing each launch
    alone, with its own seed, and averaging by hand."""
    spp, budget = 24, RES * RES * 7  # 7 samples a launch at most: launches of 6, 6, 6 and 6
    for rfilter, footprint in (("box", "film"), ("gaussian", "film"), ("gaussian", "pixel")):
        sc = wall_scene(rfilter)
        calls = []
        name = "_in_pixels" if footprint == "pixel" and rfilter != "box" else "render_pass"
        launch = getattr(guides, name)

        def counted(*args, f=launch):
            calls.append(tuple(args[-2:]))  # (spp, seed) of the launch
            return f(*args)
        monkeypatch.setattr(guides, name, counted)
        got = guides.first_hit(sc, spp, 5, footprint=footprint, lanes_per_launch=budget)
        monkeypatch.undo()
        assert [n for n, _ in calls] == [6, 6, 6, 6], (rfilter, calls)
        assert len({seed for _, seed in calls}) == 4, "each launch its own rays"
        assert calls[0][1] == 5, "one launch (few samples) stays what it was: the caller's seed"
        alone = [guides.first_hit(sc, n, seed, footprint=footprint) for n, seed in calls]
        for name in guides.Guides._fields:
            want = sum(n * getattr(g, name) for (n, _), g in zip(calls, alone)) / spp
            np.testing.assert_allclose(getattr(got, name), want, rtol=1e-6, atol=1e-6,
                                       err_msg=f"{rfilter} {footprint} {name}")
        # the checker edges are antialiased by all 24 samples, not by one launch's 6
        assert not np.allclose(got.albedo, alone[0].albedo, atol=1e-3)


def test_a_surface_without_a_diffuse_lobe_has_albedo_one_whatever_the_view():
    """Rough glass and a rough conductor have no diffuse reflectance: their albedo guide is 1 from
    every direction, not `eval_diffuse_reflectance` of their glossy lobe (measured: 36 for rough
    glass seen head-on, 1e-5 at other angles, whose ratio to a neighbour's remodulated the
    expectation of glass-of-milk's glass into black dots). A diffuse surface keeps its
    reflectance, and a blend of diffuse and conductor stays a reflectance (at most 1)."""
    cases = (
        ({"type": "roughdielectric", "alpha": 0.005, "int_ior": 1.33}, None),
        ({"type": "roughconductor", "alpha": 0.1}, None),
        ({"type": "diffuse", "reflectance": {"type": "rgb", "value": [0.2, 0.4, 0.6]}},
         [0.2, 0.4, 0.6]),
        ({"type": "blendbsdf", "weight": 0.5, "bsdf_0": {"type": "diffuse"},
          "bsdf_1": {"type": "roughconductor", "alpha": 0.1}}, "at most 1"),
    )
    for bsdf, want in cases:
        for z in (4.0, 2.5):  # head-on, and from a slant
            sc = api.load_scene({
                "type": "scene",
                "sensor": camera(z, 0) if z == 4.0 else {
                    **camera(z, 0),
                    "to_world": mi.ScalarTransform4f().look_at(
                        origin=[2.0, 0, z], target=[0, 0, 0], up=[0, 1, 0]),
                },
                "plane": {"type": "rectangle", "to_world": mi.ScalarTransform4f().scale(20),
                          "bsdf": bsdf},
            })
            got = guides.first_hit(sc, 1, 0).albedo
            if want is None:
                np.testing.assert_allclose(got, 1.0, rtol=1e-6, err_msg=f"{bsdf['type']} z={z}")
            elif want == "at most 1":
                assert got.max() <= 1.0 and got.min() > 0.0, (bsdf["type"], z, got.min(), got.max())
            else:
                np.testing.assert_allclose(got.reshape(-1, 3), [want] * RES * RES, rtol=1e-5)
