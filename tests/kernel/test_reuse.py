"""reuse=pixels (kernel/reuse/): pooled children at the first hit.

Truth from outside the pooling code: an analytic plane under a uniform sky, Mitsuba's `path`, the
tree sampler at a large n on the same camera rays, and the pools checked against the scene's
geometry. Pooled pixels are correlated, so standard errors come from independent seeds (one image
mean each).
"""

import numpy as np
import pytest

import styletrace
from styletrace.errors import SceneError, SettingsError
from styletrace.frontends import api
from styletrace.frontends.cli import main
from styletrace.gate import mi
from styletrace.kernel import reuse

T = mi.ScalarTransform4f
Z = 4.0


def film(res):
    return {
        "type": "hdrfilm",
        "width": res,
        "height": res,
        "rfilter": {"type": "box"},
        "pixel_format": "rgb",
    }


def plane_scene(res=24, albedo=0.6):
    """A diffuse plane filling the view, seen at an angle, under a constant sky of radiance 1: every
    first hit has exitant radiance albedo exactly (the plane sees only the sky)."""
    return {
        "type": "scene",
        "sensor": {
            "type": "perspective",
            "fov": 40,
            "film": film(res),
            "to_world": T().look_at(origin=[0, 1.5, 2.0], target=[0, 0, 0], up=[0, 1, 0]),
            "sampler": {"type": "independent", "sample_count": 4},
        },
        "plane": {
            "type": "rectangle",
            "to_world": T().rotate([1, 0, 0], -90) @ T().scale(50.0),
            "bsdf": {"type": "diffuse", "reflectance": {"type": "rgb", "value": albedo}},
        },
        "sky": {"type": "constant", "radiance": {"type": "rgb", "value": 1.0}},
    }


def room_scene(res=16):
    """A small diffuse ball in a large diffuse room lit by a light that faces away from the ball:
    the ball gets no direct light, only the room's indirect light, and its normals turn fast from
    pixel to pixel."""
    return {
        "type": "scene",
        "sensor": {
            "type": "perspective",
            "fov": 30,
            "film": film(res),
            "to_world": T().look_at(origin=[0, 0, 3], target=[0, 0, 0], up=[0, 1, 0]),
            "sampler": {"type": "independent", "sample_count": 4},
        },
        "room": {
            "type": "sphere",
            "radius": 6.0,
            "flip_normals": True,
            "bsdf": {"type": "diffuse", "reflectance": {"type": "rgb", "value": 0.5}},
        },
        "ball": {
            "type": "sphere",
            "radius": 0.5,
            "bsdf": {"type": "diffuse", "reflectance": {"type": "rgb", "value": 0.8}},
        },
        "light": {
            "type": "rectangle",
            "to_world": T().translate([0, 2.0, 0]) @ T().rotate([1, 0, 0], -90) @ T().scale(0.5),
            "emitter": {"type": "area", "radiance": {"type": "rgb", "value": 20.0}},
        },
    }


def seed_means(scene, integ, seeds, spp, mask=None, **kw):
    sensor = scene.sensors()[0]
    out = []
    for s in range(seeds):
        img = np.asarray(
            reuse.render_reuse(integ, scene, sensor, 1000 + s, spp, **kw), dtype=np.float64
        )[..., :3]
        out.append(img[mask].mean() if mask is not None else img.mean())
    return np.array(out)


@pytest.mark.parametrize("weights", ["balance", "pairwise"])
def test_identity_on_a_plane_under_a_uniform_sky_is_exact(weights):
    scene = mi.load_dict(plane_scene())
    integ = api.make_integrator(
        "identity", inner=2, reuse="pixels", reuse_radius=2, reuse_k=12, reuse_mis=weights
    )
    means = seed_means(scene, integ, 6, 8)
    z = (means.mean() - 0.6) / (means.std(ddof=1) / np.sqrt(len(means)))
    assert abs(z) < Z, f"image mean {means.mean()} vs exact 0.6: z = {z}"


@pytest.fixture(scope="module")
def room():
    scene = mi.load_dict(room_scene())
    res = 16
    yy, xx = np.mgrid[0:res, 0:res]
    c = (res - 1) / 2
    rpix = np.tan(np.arcsin(0.5 / 3)) / np.tan(np.radians(15)) * res / 2
    mask = (xx - c) ** 2 + (yy - c) ** 2 < (0.85 * rpix) ** 2  # inside the ball's silhouette
    path = mi.load_dict({"type": "path"})
    refs = np.array(
        [
            np.asarray(mi.render(scene, integrator=path, spp=1024, seed=s), dtype=np.float64)[
                ..., :3
            ][mask].mean()
            for s in range(4)
        ]
    )
    return scene, mask, refs


def test_mixture_weights_are_unbiased_where_own_pdf_weights_are_not(room, monkeypatch):
    """Neighbours accepted whatever their normals (a wide-open acceptance): the balance
    (mixture-pdf) and pairwise weights stay unbiased against Mitsuba's `path` (v itself covers
    its whole hemisphere); dividing each pooled sample by its own density misses the directions a
    neighbour cannot sample, and the same 4-sigma test rejects it (measured: 10 % darker)."""
    scene, mask, refs = room
    monkeypatch.setattr(reuse.pool, "NORMAL_MIN", -1.0)
    monkeypatch.setattr(reuse.pool, "DEPTH_TOL", 10.0)
    integ = api.make_integrator("identity", inner=1, reuse="pixels", reuse_radius=3, reuse_k=48)

    def z(weights):
        means = seed_means(scene, integ, 6, 64, mask, weights=weights)
        se = np.hypot(
            means.std(ddof=1) / np.sqrt(len(means)), refs.std(ddof=1) / np.sqrt(len(refs))
        )
        return (means.mean() - refs.mean()) / se

    for weights in ("balance", "pairwise"):
        z_mixture = z(weights)
        assert abs(z_mixture) < Z, f"{weights} weights: z = {z_mixture}"
    z_own = z("own")
    assert z_own < -Z, f"own pdf: z = {z_own} (expected darker than path)"


def test_cel_with_reuse_beats_the_tree_with_twice_the_children():
    """Same seed, so the same camera rays in every render: the error is the inner estimate's
    alone. Reference: the tree sampler at n = 256 children per camera sample. Pooling K = 8
    neighbours' 4 children must beat doubling the tree's children (4 -> 8); with the pool
    switched off it is the tree at n = 4 (measured MSE 0.032 pooled, 0.038 tree n = 8, 0.052 tree
    n = 4)."""
    kw = dict(style="cel", width=32, height=32, spp=2, seed=3)
    ref = styletrace.render("cornell-box", inner=256, **kw)
    mse = {n: ((styletrace.render("cornell-box", inner=n, **kw) - ref) ** 2).mean() for n in (4, 8)}
    pooled = (
        (styletrace.render("cornell-box", inner=4, reuse="pixels", reuse_k=8, **kw) - ref) ** 2
    ).mean()
    assert mse[8] < mse[4]
    assert pooled < mse[8], f"MSE with reuse {pooled:.3e}, tree n=8 {mse[8]:.3e}, n=4 {mse[4]:.3e}"


def test_same_seed_same_camera_rays_as_the_tree():
    """A closed-form style (no children, never pooled) is a function of the first hit alone: with
    reuse it must give the tree's image bit for bit, so both place the same camera rays (the
    premise of the MSE comparisons above and in docs/reuse.md)."""
    kw = dict(style="gooch", width=24, height=24, spp=2, seed=4)
    assert np.array_equal(
        styletrace.render("cornell-box", **kw),
        styletrace.render("cornell-box", reuse="pixels", **kw),
    )


def two_slots_scene(res=32):
    """Two coplanar rectangles meeting at x = 0 (the film's middle column boundary), each with
    its own `styled` style, seen straight down under a sky."""

    def half(x, style):
        return {
            "type": "rectangle",
            "to_world": T().translate([x, 0, 0])
            @ T().rotate([1, 0, 0], -90)
            @ T().scale([1.0, 2.0, 1.0]),
            "bsdf": {
                "type": "styled",
                "style": style,
                "inner_samples": 2,
                "bsdf": {"type": "diffuse", "reflectance": {"type": "rgb", "value": 0.5}},
            },
        }

    return {
        "type": "scene",
        "sensor": {
            "type": "orthographic",
            "film": film(res),
            "to_world": T().look_at(origin=[0, 3, 0], target=[0, 0, 0], up=[0, 0, -1])
            @ T().scale(1.0),
            "sampler": {"type": "independent", "sample_count": 4},
        },
        "left": half(-1.0, "cel"),
        "right": half(1.0, "identity"),
        "sky": {"type": "constant", "radiance": {"type": "rgb", "value": 1.0}},
    }


def test_pools_never_cross_style_slots():
    scene = mi.load_dict(two_slots_scene())
    integ = api.make_integrator("identity", inner=2, reuse="pixels", reuse_radius=2, reuse_k=24)
    keep = {}
    reuse.render_reuse(integ, scene, scene.sensors()[0], 0, 2, keep=keep)
    half = keep["width"] // 2
    sizes, crossing = [], 0
    for members in reuse.pool_pixels(keep):
        side = members[0][0] < half
        crossing += sum((x < half) != side for x, _ in members)
        sizes.append(len(members))
    assert crossing == 0
    # the pools are not trivially empty: a neighbour on the same side is taken
    assert np.mean(sizes) > 10


def test_null_surfaces_refused_in_one_line():
    d = plane_scene(8)
    d["plane"]["bsdf"] = {"type": "mask", "opacity": 0.5, "material": d["plane"]["bsdf"]}
    scene = mi.load_dict(d)
    integ = api.make_integrator("identity", reuse="pixels")
    with pytest.raises(SceneError, match="null-scattering") as err:
        reuse.render_reuse(integ, scene, scene.sensors()[0], 0, 1)
    assert "\n" not in str(err.value)


def test_media_refused_in_one_line():
    d = plane_scene(8)
    d["fog"] = {"type": "homogeneous", "sigma_t": 0.5, "albedo": 0.5}
    d["sensor"]["medium"] = {"type": "ref", "id": "fog"}
    scene = mi.load_dict(d)
    integ = api.make_integrator("identity", reuse="pixels")
    with pytest.raises(SceneError, match="participating media") as err:
        reuse.render_reuse(integ, scene, scene.sensors()[0], 0, 1)
    assert "\n" not in str(err.value)


BAD = [
    (dict(reuse="neighbours"), "bad value 'neighbours' for 'reuse'"),
    (dict(reuse="pixels", reuse_radius=0), "bad value 0 for 'reuse_radius'"),
    (dict(reuse="pixels", reuse_radius=1, reuse_k=9), "bad value 9 for 'reuse_k'"),
    (dict(reuse="pixels", reuse_radius=8, reuse_k=64), "bad value 64 for 'reuse_k'"),
    (dict(reuse="pixels", reuse_mis="power"), "bad value 'power' for 'reuse_mis'"),
    (
        dict(reuse="pixels", stylize="first_object_hit"),
        "reuse=pixels pools samples at the first hit",
    ),
    (dict(reuse="pixels", style="gamma", estimator="series"), "supports 'direct' only"),
    (dict(reuse="pixels", style="acp"), "cannot be used with reuse=pixels"),
    (
        dict(reuse="pixels", style="gamma", inner="4:16", estimator="series"),
        "bad value '4:16' for 'inner_samples'",
    ),
    (dict(reuse="pixels", lines=True), "bad value True for 'lines' with reuse=pixels"),
    (dict(reuse="pixels", aovs=True), "bad value True for 'aovs' with reuse=pixels"),
]


@pytest.mark.parametrize("values,message", BAD, ids=[m for _, m in BAD])
def test_bad_settings_one_line(values, message):
    with pytest.raises(SettingsError) as err:
        api.make_integrator(**values)
    assert message in str(err.value) and "\n" not in str(err.value)


def test_command_line(tmp_path, capsys):
    out = tmp_path / "r.exr"
    assert (
        main(
            [
                "render",
                "-q",
                "--style",
                "cel",
                "--width",
                "16",
                "--height",
                "16",
                "--spp",
                "2",
                "--inner",
                "2",
                "--set",
                "reuse=pixels",
                "--reuse-k",
                "4",
                "-o",
                str(out),
            ]
        )
        == 0
    )
    assert out.exists()
    assert (
        main(
            [
                "render",
                "-q",
                "--reuse",
                "pixels",
                "--style",
                "identity",
                "--stylize",
                "first_object_hit",
                "-o",
                str(out),
            ]
        )
        == 2
    )
    err = capsys.readouterr().err.strip()
    assert err.startswith("styletrace: error: ") and "first hit" in err and "\n" not in err


def test_expectation_buffers_refuse_reuse():
    from styletrace.lookdev.record import render_buffer

    with pytest.raises(SettingsError, match="cannot be buffered") as err:
        render_buffer("cornell-box", style="cel", spp=1, inner=2, width=8, height=8, reuse="pixels")
    assert "\n" not in str(err.value)
