"""Styled BSDFs inside wrappers (twosided, mask, blendbsdf) and inside shapegroups used by
instances are found and stylized (kernel/scene_graph.py); surfaces where a style cannot apply are
refused in one line."""
import numpy as np
import pytest

from styletrace.errors import SceneError
from styletrace.frontends.api import make_integrator, passes
from styletrace.gate import mi
from styletrace.kernel.scene_graph import SceneGraph

T = mi.ScalarTransform4f
RES = 24


def base():
    return {
        "type": "scene",
        "sensor": {
            "type": "perspective",
            "fov": 35,
            "to_world": T().look_at(origin=[0, 0, 6], target=[0, 0, 0], up=[0, 1, 0]),
            "sampler": {"type": "independent"},
            "film": {"type": "hdrfilm", "width": RES, "height": RES, "rfilter": {"type": "box"}},
        },
        "sky": {"type": "constant", "radiance": {"type": "rgb", "value": [0.5] * 3}},
        "lamp": {
            "type": "point",
            "position": [2, 3, 4],
            "intensity": {"type": "rgb", "value": [30.0] * 3},
        },
    }


def diffuse():
    return {"type": "diffuse", "reflectance": {"type": "rgb", "value": [0.6, 0.3, 0.2]}}


def styled(style, nested):
    return {"type": "styled", "style": style, "inner_samples": 4, "b": nested}


def render(d, seed=7, spp=4):
    *_, last = passes(mi.load_dict(d), make_integrator("identity", inner=4), spp, seed=seed)
    return last.image


@pytest.mark.parametrize("wrapper", ["twosided", "blendbsdf"])
def test_a_wrapped_styled_bsdf_renders_as_its_style(wrapper):
    """A card with twosided(styled cel(diffuse)) renders as the card with styled cel(diffuse),
    seen from the front where the two BSDFs are one (same seed: the same paths); a blend of a
    styled BSDF with itself likewise. Before wrappers were looked into, the card took the
    integrator's identity style."""
    plain, wrapped = base(), base()
    plain["card"] = {
        "type": "rectangle",
        "to_world": T().scale(2),
        "bsdf": styled("cel", diffuse()),
    }
    inner = styled("cel", diffuse())
    bsdf = (
        {"type": "twosided", "b": inner}
        if wrapper == "twosided"
        else {
            "type": "blendbsdf",
            "weight": 0.3,
            "a": {"type": "ref", "id": "s"},
            "b": {"type": "ref", "id": "s"},
        }
    )
    if wrapper == "blendbsdf":
        wrapped["s"] = {**inner, "id": "s"}
    wrapped["card"] = {"type": "rectangle", "to_world": T().scale(2), "bsdf": bsdf}
    a, b = render(plain), render(wrapped)
    unstyled = base()
    unstyled["card"] = {"type": "rectangle", "to_world": T().scale(2), "bsdf": diffuse()}
    assert np.abs(render(unstyled) - a).max() > 0.05  # cel is visibly not identity here
    assert np.allclose(a, b, rtol=1e-4, atol=1e-5), f"max difference {np.abs(a - b).max()}"


def test_a_styled_bsdf_in_an_instanced_shapegroup_is_stylized_in_every_instance():
    """Two instances of a shapegroup holding a gooch-styled sphere (closed form: deterministic)
    render as two styled spheres placed directly."""
    where = [[-1.2, 0, 0], [1.2, 0, 0]]
    direct, grouped = base(), base()
    for i, c in enumerate(where):
        direct[f"ball{i}"] = {
            "type": "sphere",
            "center": c,
            "radius": 0.8,
            "bsdf": styled("gooch", diffuse()),
        }
    grouped["group"] = {
        "type": "shapegroup",
        "ball": {"type": "sphere", "radius": 0.8, "bsdf": styled("gooch", diffuse())},
    }
    for i, c in enumerate(where):
        grouped[f"copy{i}"] = {"type": "instance", "shapegroup": {"type": "ref", "id": "group"},
                               "to_world": T().translate(c)}
    a, b = render(direct), render(grouped)
    assert np.allclose(a, b, rtol=1e-3, atol=1e-4), f"max difference {np.abs(a - b).max()}"


def test_wrappers_and_instances_are_registered():
    d = base()
    d["card"] = {"type": "rectangle", "bsdf": {"type": "twosided", "b": styled("cel", diffuse())}}
    d["group"] = {
        "type": "shapegroup",
        "ball": {"type": "sphere", "bsdf": styled("gooch", diffuse())},
    }
    d["copy"] = {"type": "instance", "shapegroup": {"type": "ref", "id": "group"}}
    graph = SceneGraph(mi.load_dict(d))
    kinds = sorted(
        (s.slot.style.name, ptrs[0] is s, [p.class_name() for p in ptrs[1:]])
        for s, ptrs, _ in graph.styled
    )
    assert kinds == [("cel", True, ["TwoSidedBRDF"]), ("gooch", True, [])]


@pytest.mark.parametrize(
    "bsdf, message",
    [
        (
            {
                "type": "blendbsdf",
                "weight": 0.5,
                "a": styled("cel", diffuse()),
                "b": styled("gooch", diffuse()),
            },
            "holds 2 'styled' BSDFs",
        ),
        (
            {"type": "twosided", "a": styled("cel", diffuse()), "b": styled("gooch", diffuse())},
            "holds 2 'styled' BSDFs",
        ),
        (
            styled("cel", {"type": "twosided", "b": styled("gooch", diffuse())}),
            "holds another 'styled' BSDF",
        ),
    ],
)
def test_a_surface_with_two_styles_is_refused_in_one_line(bsdf, message):
    d = base()
    d["card"] = {"type": "rectangle", "bsdf": bsdf}
    with pytest.raises(SceneError, match=message) as info:
        passes(mi.load_dict(d), make_integrator("identity", inner=2), 1, seed=0).__next__()
    assert "\n" not in str(info.value)


def test_a_scene_with_a_medium_is_seen_and_renders():
    """A shape's interior medium or the sensor's is found (the integrator then traces volume.py's
    walk), and the scene renders (test_media.py compares it with Mitsuba's volpath)."""
    d = base()
    d["fog"] = {"type": "homogeneous", "sigma_t": 1.0, "albedo": 0.5}
    d["ball"] = {
        "type": "sphere",
        "bsdf": {"type": "null"},
        "interior": {"type": "ref", "id": "fog"},
    }
    assert SceneGraph(mi.load_dict(d)).has_media is True
    assert SceneGraph(mi.load_dict(base())).has_media is False
    image = next(passes(mi.load_dict(d), make_integrator("identity", inner=2), 1, seed=0)).image
    assert np.all(np.isfinite(image)) and image.mean() > 0
