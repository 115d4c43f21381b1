"""The settings a scene's own Mitsuba integrator hands to `stylized` (pipeline/carried.py), per
wrapper and type.

Each case is an XML file whose integrator sets max_depth (through a $parameter, so the defines
matter) and hide_emitters; the render pipeline's integrator must keep both. Wrappers (`moment`,
`aov`) report neither their nested integrator's hide_emitters nor (for the Python integrators) its
depths in a form a regex reads.
"""
import pytest

import styletrace
from styletrace.errors import SceneError
from styletrace.gate import mi
from styletrace.pipeline.carried import carried_settings, declared, loaded
from styletrace.pipeline.job import Job
from styletrace.pipeline.resolve import resolve
from styletrace.scene.loading import SceneWarning, load_scene

styletrace.init()

SCENE = """<scene version="3.0.0">
  <default name="depth" value="7"/>
  {integrator}
  <sensor type="perspective">
    <film type="hdrfilm"><integer name="width" value="4"/><integer name="height" value="4"/></film>
    <sampler type="independent"><integer name="sample_count" value="2"/></sampler>
  </sensor>
  <shape type="sphere"><bsdf type="diffuse"/></shape>
  <emitter type="constant"/>
</scene>
"""
OWN = '<integer name="max_depth" value="$depth"/><integer name="rr_depth" value="2"/>' \
      '<boolean name="hide_emitters" value="true"/>'
CASES = {
    "path": f'<integrator type="path">{OWN}</integrator>',
    "moment": f'<integrator type="moment"><integrator type="path">{OWN}</integrator></integrator>',
    "aov": f'<integrator type="aov"><string name="aovs" value="dd:depth"/>'
    f'<integrator type="path">{OWN}</integrator></integrator>',
    "moment_of_prb": f'<integrator type="moment"><integrator '
    f'type="prb">{OWN}</integrator></integrator>',
    "ptracer": f'<integrator type="ptracer">{OWN}</integrator>',
    "volpathmis": f'<integrator type="volpathmis">{OWN}</integrator>',
    "prb": f'<integrator type="prb">{OWN}</integrator>',
    "prbvolpath": f'<integrator type="prbvolpath">{OWN}</integrator>',
}


def write(tmp_path, integrator: str) -> str:
    path = tmp_path / "scene.xml"
    path.write_text(SCENE.format(integrator=integrator))
    return str(path)


@pytest.mark.parametrize("kind", sorted(CASES))
def test_max_depth_rr_depth_and_hide_emitters_are_carried(tmp_path, kind):
    path = write(tmp_path, CASES[kind])
    r = resolve(Job(scene=path, defines={"depth": "3"}, lanes_per_pass=1 << 20))
    s = r.integrator.settings
    assert (s.max_depth, s.rr_depth, s.hide_emitters) == (3, 2, True), kind
    assert s.style.name == "identity"  # the Python API's default style over the carried settings


def test_direct_carries_one_bounce_and_hide_emitters(tmp_path):
    path = write(
        tmp_path,
        '<integrator type="direct"><boolean name="hide_emitters" value="true"/></integrator>',
    )
    s = resolve(Job(scene=path, lanes_per_pass=1 << 20)).integrator.settings
    assert (s.max_depth, s.hide_emitters) == (2, True)


def test_without_defines_the_files_default_holds(tmp_path):
    path = write(tmp_path, CASES["moment"])
    assert resolve(Job(scene=path, lanes_per_pass=1 << 20)).integrator.settings.max_depth == 7


def test_given_values_win_over_carried_ones(tmp_path):
    path = write(tmp_path, CASES["aov"])
    s = resolve(
        Job(scene=path, given={"max_depth": 5, "hide_emitters": False}, lanes_per_pass=1 << 20)
    ).integrator.settings
    assert (s.max_depth, s.rr_depth, s.hide_emitters) == (5, 2, False)


def test_the_declaration_sees_through_wrappers_where_the_object_does_not(tmp_path):
    """Why the declaration is read at all: a loaded `moment` says hide_emitters False whatever
    its nested says."""
    path = write(tmp_path, CASES["moment"])
    scene = load_scene(path)
    assert "hide_emitters" not in loaded(scene.integrator())
    assert declared(path)["hide_emitters"] is True and declared(path)["type"] == "path"
    assert carried_settings(scene, path)["hide_emitters"] is True


def test_a_loaded_scene_alone_still_carries_what_its_object_reports():
    """An mi.Scene has no source to read: the object's attributes (prb) and description (path)
    serve."""
    for kind, expect in (
        ("path", 3),
        ("prb", 3),
        ("prbvolpath", 3),
        ("volpathmis", 3),
        ("ptracer", 3),
    ):
        scene = mi.load_dict(
            {
                "type": "scene",
                "integrator": {"type": kind, "max_depth": 3, "rr_depth": 2},
                "s": {"type": "sphere"},
            }
        )
        assert carried_settings(scene) == {"max_depth": expect, "rr_depth": 2}, kind
    prb = mi.load_dict({"type": "scene", "integrator": {"type": "prb"}, "s": {"type": "sphere"}})
    assert carried_settings(prb)["max_depth"] == 6  # Mitsuba's own default for prb, not ours (-1)


def test_a_scene_dict_is_read_like_a_file():
    d = {
        "type": "scene",
        "integrator": {
            "type": "moment",
            "n": {"type": "path", "max_depth": 4, "hide_emitters": True},
        },
        "s": {"type": "sphere"},
        "sensor": {"type": "perspective", "film": {"type": "hdrfilm", "width": 4, "height": 4}},
    }
    s = resolve(Job(scene=d, lanes_per_pass=1 << 20)).integrator.settings
    assert (s.max_depth, s.hide_emitters) == (4, True)


def test_a_stylized_integrator_in_the_file_is_the_base(tmp_path):
    path = write(
        tmp_path,
        '<integrator type="stylized"><string name="style" value="cel"/>'
        '<integer name="max_depth" value="$depth"/><boolean name="hide_emitters" value="true"/>'
        '<string name="thresholds" value="0.4"/></integrator>',
    )
    s = resolve(Job(scene=path, defines={"depth": "2"}, lanes_per_pass=1 << 20)).integrator.settings
    assert (s.style.name, s.max_depth, s.hide_emitters) == ("cel", 2, True)
    s = resolve(
        Job(scene=path, given={"inner_samples": 3}, lanes_per_pass=1 << 20)
    ).integrator.settings
    assert (s.style.name, s.max_depth, s.inner) == ("cel", 7, (3,))


@pytest.mark.parametrize("wrapper", ["moment", "aov"])
def test_a_stylized_integrator_nested_in_a_wrapper_is_the_base(tmp_path, wrapper):
    """Its own values (style, parameters, depths) are the base, as for a `stylized` integrator at
    the top."""
    extra = '<string name="aovs" value="dd:depth"/>' if wrapper == "aov" else ""
    nested = (
        '<integrator type="stylized"><string name="style" value="cel"/><string name="levels" '
        'value="0.2,0.9"/>'
        '<integer name="max_depth" value="$depth"/></integrator>'
    )
    path = write(tmp_path, f'<integrator type="{wrapper}">{extra}{nested}</integrator>')
    s = resolve(Job(scene=path, defines={"depth": "4"}, lanes_per_pass=1 << 20)).integrator.settings
    assert (s.style.name, s.max_depth) == ("cel", 4)
    assert s.style.levels == (0.2, 0.9)
    given = resolve(
        Job(scene=path, given={"max_depth": 2}, lanes_per_pass=1 << 20)
    ).integrator.settings
    # what the caller gives is laid over it
    assert (given.style.name, given.max_depth) == ("cel", 2)


# ---- an integrator chosen through a <default> (Mitsuba's convention: type="$integrator") ---------
def by_default(kind: str, props: str = "", wrapper: str = "") -> str:
    """The integrator element in Mitsuba's convention, its type a $parameter whose default is
    `kind`."""
    inner = (
        f'<default name="integrator" value="{kind}"/><integrator '
        f'type="$integrator">{props}</integrator>'
    )
    if wrapper:
        inner = inner.replace(
            "<integrator type=", f'<integrator type="{wrapper}"><integrator type=', 1
        )
        inner += "</integrator>"
    return inner


def settings(path, **defines):
    s = resolve(Job(scene=path, defines=defines, lanes_per_pass=1 << 20)).integrator.settings
    return s.max_depth, s.rr_depth, s.hide_emitters


def test_direct_through_a_default_carries_exactly_what_direct_written_out_does(tmp_path):
    hide = '<boolean name="hide_emitters" value="true"/>'
    written = write(tmp_path, f'<integrator type="direct">{hide}</integrator>')
    expected = settings(written)
    assert expected[0] == 2 and expected[2] is True
    (tmp_path / "d").mkdir()
    path = write(tmp_path / "d", by_default("direct", hide))
    assert settings(path) == expected
    # not replaced as an unknown '$integrator'
    assert "DirectIntegrator" in str(load_scene(path).integrator())


def test_a_define_picks_the_integrator_and_its_settings(tmp_path):
    """`-D integrator=path` over a file whose default is `direct`: path's own settings
    (unbounded, rr 5)."""
    path = write(tmp_path, by_default("direct", '<boolean name="hide_emitters" value="true"/>'))
    assert settings(path, integrator="path") == (-1, 5, True)
    assert "PathIntegrator" in str(load_scene(path, defines={"integrator": "path"}).integrator())


@pytest.mark.parametrize("wrapper", ["", "moment", "aov"])
def test_every_property_through_a_parameter_is_carried(tmp_path, wrapper):
    props = ('<string name="aovs" value="dd:depth"/>' if wrapper == "aov" else "")
    text = by_default("path", OWN, wrapper).replace('<integrator type="aov">',
                                                   f'<integrator type="aov">{props}')
    path = write(tmp_path, text)
    assert settings(path) == (7, 2, True)
    assert settings(path, depth="3", integrator="volpath") == (3, 2, True)


@pytest.mark.parametrize("wrapper", ["moment", "aov"])
def test_direct_nested_in_a_wrapper_is_one_bounce(tmp_path, wrapper):
    """A wrapper's loaded object reports no depth of its nested `direct`: the declaration says 2."""
    extra = '<string name="aovs" value="dd:depth"/>' if wrapper == "aov" else ""
    path = write(
        tmp_path, f'<integrator type="{wrapper}">{extra}<integrator type="direct"/></integrator>'
    )
    assert settings(path)[0] == 2
    (tmp_path / "d").mkdir()
    path = write(tmp_path / "d", by_default("direct", wrapper=wrapper).replace(
        f'<integrator type="{wrapper}">', f'<integrator type="{wrapper}">{extra}'))
    assert settings(path)[0] == 2


def test_an_unknown_type_through_a_default_is_replaced_and_its_define_accepted(tmp_path):
    path = write(
        tmp_path,
        '<default name="kind" value="sre"/><integrator type="$kind">'
        '<integer name="max_depth" value="$depth"/><float name="sharpness" '
        'value="2"/></integrator>',
    )
    with pytest.warns(
        SceneWarning,
        match="integrator 'sre' is not a Mitsuba plugin: rendering with "
        "stylized, keeping max_depth=7; dropped sharpness",
    ):
        assert settings(path)[0] == 7
    # the define was used by the type only, which the replacement drops: Mitsuba must not refuse it
    # as unused
    with pytest.warns(SceneWarning, match="integrator 'toon' .* keeping max_depth=3;"):
        assert settings(path, kind="toon", depth="3")[0] == 3
    with pytest.raises(SceneError, match="uses no parameter nope"):
        settings(path, nope="1")
