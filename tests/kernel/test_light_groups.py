"""Light groups (docs/light_groups.md): each group's light its own expectation at the first hit,
styled by its own style, from the same paths.

Truth from outside the code under test: the render without groups (identity in every group is
the same estimate of the same paths, summed by group), and a furnace whose groups' first-hit
radiance is known exactly: a diffuse sphere of albedo rho emitting E2 (its own group: every
point of a convex emitter sees none of it) under a constant sky E1 (the other group, rho * E1 at
every point). Pixels inside the silhouette are independent draws of one estimator, which gives
the standard errors (as tests/kernel/test_furnace.py).
"""
import numpy as np
import pytest
from helpers.furnace import sphere_mask

from styletrace.errors import SceneError, SettingsError
from styletrace.frontends.api import make_integrator, passes, scene_dict
from styletrace.gate import mi

Z = 4.0
RHO, E1, E2 = np.array([0.8, 0.5, 0.3]), 1.0, np.array([0.2, 0.4, 0.1])
RES = 48


def two_light_box(mark: str = "", ceiling: str = "") -> mi.Scene:
    """The Cornell box with a point light beside its ceiling light, the point light marked
    `mark`, the ceiling light's shape `ceiling`."""
    d = scene_dict("cornell-box", 12, 12)
    d["light" + ceiling] = d.pop("light")
    d["sensor"]["sampler"] = {"type": "independent", "sample_count": 4}
    d["fill" + mark] = {"type": "point", "position": [0.3, 0.5, 0.2],
                        "intensity": {"type": "rgb", "value": [0.5, 0.5, 0.5]}}
    return mi.load_dict(d)


def last(scene, integ, spp=2, seed=3):
    return list(passes(scene, integ, spp, seed=seed))[-1]


def test_no_groups_is_the_render_without_them():
    """No light_groups property, an empty one, and marks no group declares: the same image, bit
    for bit (none of the group code is traced)."""
    plain = last(two_light_box(), make_integrator("cel", inner=2)).image
    empty = last(two_light_box(), make_integrator("cel", inner=2, light_groups="")).image
    marked = last(two_light_box("__lg_fill"), make_integrator("cel", inner=2)).image
    assert np.array_equal(plain, empty)
    assert np.array_equal(plain, marked)


def test_identity_in_every_group_is_the_ungrouped_render():
    """Identity in every group (the ceiling light by its shape's mark, the point light by its own,
    the white sky by none): the image equals the render without groups and the sum of the group
    passes equals the image, within float rounding (the same paths)."""
    plain = last(two_light_box(), make_integrator("identity", inner=3)).image
    grouped = last(two_light_box("__lg_fill", "__lg_key"),
                   make_integrator("identity", inner=3, light_groups="key:identity;fill:identity"))
    parts = grouped.light_groups
    assert list(parts) == ["default", "key", "fill"]
    assert np.allclose(grouped.image, plain, rtol=1e-5, atol=1e-6)
    assert np.allclose(sum(parts.values()), grouped.image, rtol=1e-5, atol=1e-6)
    # each lit group holds light of its own: neither pass is the whole image
    assert parts["fill"].max() > 0.01 and parts["key"].max() > 0.01


def furnace() -> mi.Scene:
    d = scene_dict("furnace", RES, RES)
    d["sensor"]["sampler"] = {"type": "independent", "sample_count": 1}
    d["sphere"]["bsdf"]["reflectance"]["value"] = list(RHO)
    d["sphere"]["emitter"] = {"type": "area", "radiance": {"type": "rgb", "value": list(E2)}}
    d["env__lg_sky"] = d.pop("env")
    d["env__lg_sky"]["radiance"]["value"] = [E1] * 3
    return mi.load_dict(d)


def test_furnace_groups_styled_each_converge_to_the_sum_of_styled_groups():
    """gamma by the unbiased power series on the sky's group, identity on the sphere's own
    emission: the image's mean is gamma(rho E1) + E2 within Z standard errors (the spread of the
    pixels over seeds), the groups' passes hold each, and g of the sum is ruled out."""
    scene, mask = furnace(), sphere_mask(RES)
    integ = make_integrator("identity", inner=4, light_groups="sky:gamma", **{
        "sky.estimator": "series", "sky.exposure": 1.0, "sky.inner_samples": 4})
    runs = [last(scene, integ, spp=1, seed=s) for s in range(6)]
    vals = np.concatenate([r.image[mask] for r in runs]).astype(np.float64)
    sky = np.concatenate([r.light_groups["sky"][mask] for r in runs]).astype(np.float64)
    own = np.concatenate([r.light_groups["default"][mask] for r in runs]).astype(np.float64)
    gamma = lambda x: x ** (1 / 2.2)  # noqa: E731
    exact = gamma(RHO * E1) + E2
    se = vals.std(0, ddof=1) / np.sqrt(len(vals))
    z = (vals.mean(0) - exact) / se
    assert np.all(np.abs(z) < Z), f"mean {vals.mean(0)} vs {exact}: z = {z}"
    assert np.allclose(own, E2, rtol=1e-5)
    z_sky = (sky.mean(0) - gamma(RHO * E1)) / (sky.std(0, ddof=1) / np.sqrt(len(sky)))
    assert np.all(np.abs(z_sky) < Z), f"sky {sky.mean(0)}: z = {z_sky}"
    wrong = gamma(RHO * E1 + E2)  # one style over all the light: what groups are not
    assert np.all(np.abs(vals.mean(0) - wrong) > 10 * se)


@pytest.mark.parametrize("values, named", [
    (dict(stylize="first_n_hits", stylize_depth=2), "'stylize'"),
    (dict(reuse="pixels"), "'reuse'"),
    (dict(lines=True), "'lines'"),
    (dict(aovs=True), "'aovs'"),
    (dict(style="gamma", estimator="series", expansion_pass=16), "'expansion_pass'"),
    (dict(firefly=4.0), "'firefly'"),
    (dict(inner_samples="4:16"), "'inner_samples'"),
    (dict(style="gooch"), "'gooch'"),
    ({"key.levels": "0.5"}, "'key.levels'"),
    (dict(light_groups="default:cel"), "'default'"),
    (dict(light_groups="fill"), "'fill'"),
])
def test_unsupported_settings_are_refused_in_one_line(values, named):
    values = {"light_groups": "fill:identity", **values}
    with pytest.raises(SettingsError) as err:
        make_integrator(**values)
    assert named in str(err.value) and "\n" not in str(err.value)


@pytest.mark.parametrize("mark, named", [("__lg_key", "'key'"), ("", "'fill'")])
def test_scene_marks_must_match_the_groups(mark, named):
    """A mark no group declares, and a group no emitter carries: one line each."""
    integ = make_integrator("identity", inner=1, light_groups="fill:identity")
    with pytest.raises(SceneError) as err:
        last(two_light_box(mark), integ, spp=1)
    assert named in str(err.value) and "\n" not in str(err.value)


def test_a_dotted_key_of_no_declared_group_is_the_styles_and_refused_by_it():
    """`fill.levels` without a group `fill` is the style's key, refused by name; a composed style's
    own dotted keys (`contrast.c`) are not taken for a group's."""
    from styletrace.config import settings as S
    from styletrace.errors import SettingsError
    with pytest.raises(SettingsError, match="unknown property 'fill.levels'"):
        S.parse({"style": "cel", "light_groups": "key:identity", "fill.levels": "0.1,0.2,0.3"})
    parsed = S.parse({"style": "contrast+sepia", "contrast.c": 1.6})
    assert parsed.light_groups == ()
