"""The integrator's settings: defaults, parsing once, refinement, the estimator registry, errors."""
import re

import pytest

import styletrace
from styletrace.config import estimator_registry, settings
from styletrace.errors import SettingsError, StyleError
from styletrace.frontends import api
from styletrace.frontends.cli import main
from styletrace.styles import style_class, style_names

styletrace.init()


def test_defaults_come_from_the_table():
    s = settings.parse({})
    assert s.style.name == settings.DEFAULTS["style"] == "identity"
    assert s.slot.estimator == settings.DEFAULTS["estimator"] == "direct"
    assert (s.stylize, s.stylize_depth, s.max_depth, s.rr_depth) == ("first_hit", 1, -1, 5)
    assert s.inner == (max(style_class("identity").default_inner, 1),)
    assert settings.parse({"style": "cel"}).inner == (style_class("cel").default_inner,)


@pytest.mark.parametrize(
    "raw,expected",
    [(3, (3,)), ("8,4", (8, 4)), ((8, 4), (8, 4)), ([2, 3], (2, 3)), ("5", (5,)), (4.0, (4,))],
)
def test_inner_samples_spellings(raw, expected):
    assert settings.parse_inner(raw, 1) == expected


@pytest.mark.parametrize("raw", [0, "0", 2.7, "2.7", [2.7], "x", "", True])
def test_bad_inner_samples_are_refused_not_truncated(raw):
    with pytest.raises(
        SettingsError,
        match=r"bad value .* for 'inner_samples': expected an integer in \[1, 4294967294\]",
    ):
        settings.parse_inner(raw, 1)


def test_the_api_hands_inner_counts_over_as_they_are():
    integ = api.make_integrator("saturation", inner=(2, 3), stylize="first_n_hits", stylize_depth=2)
    assert integ.settings.inner == (2, 3) and integ.values["inner_samples"] == (2, 3)


def test_inner_samples_are_parsed_once_from_flag_to_kernel(monkeypatch, tmp_path):
    calls = []
    real = settings.parse_inner

    def counting(raw, default):
        calls.append(raw)
        return real(raw, default)

    monkeypatch.setattr(settings, "parse_inner", counting)
    out = tmp_path / "x.exr"
    assert (
        main(
            [
                "render",
                "--inner",
                "3",
                "--spp",
                "1",
                "--width",
                "8",
                "--height",
                "8",
                "-q",
                "-o",
                str(out),
            ]
        )
        == 0
    )
    assert calls == ["3"]


def test_refine_drops_the_old_styles_parameters_only_when_the_style_changes():
    base = {"style": "cel", "levels": "0.1,0.9", "inner_samples": 8, "max_depth": 6}
    same = settings.refine_values(base, {"inner_samples": 2})
    assert same == {"style": "cel", "levels": "0.1,0.9", "inner_samples": 2, "max_depth": 6}
    other = settings.refine_values(base, {"style": "gamma"})
    assert other == {"style": "gamma", "inner_samples": 8, "max_depth": 6}
    assert settings.parse(other).style.name == "gamma"


def test_settings_errors_have_their_own_type():
    with pytest.raises(SettingsError, match="bad value 'everywhere' for 'stylize'"):
        settings.parse({"stylize": "everywhere"})
    with pytest.raises(SettingsError, match="unknown property 'foo'"):
        settings.parse({"foo": 1})
    with pytest.raises(SettingsError, match="bad value 0 for 'max_depth'"):
        settings.parse({"max_depth": 0})
    with pytest.raises(StyleError, match="unknown style 'nope'"):
        settings.parse({"style": "nope"})
    assert not issubclass(SettingsError, StyleError) and not issubclass(StyleError, SettingsError)


def test_the_estimator_registry_mirrors_the_forms():
    assert estimator_registry.estimator_names()[0] == "direct"
    for name in style_names():
        style = style_class(name)()
        ok = estimator_registry.applicable(style)
        assert "direct" in ok
        form = style.form()
        assert ("telescoping" in ok) == (form is not None)
        for kind in estimator_registry.kinds():
            assert kind.doc and kind.inner and callable(kind.build)
            if kind.name in ok:
                assert estimator_registry.check_estimator(kind.name, style) == kind.name
            else:
                with pytest.raises(
                    SettingsError, match=f"estimator '{kind.name}' does not apply to style '{name}'"
                ):
                    estimator_registry.check_estimator(kind.name, style)
    with pytest.raises(
        SettingsError, match="unknown estimator 'magic': available are direct, affine"
    ):
        estimator_registry.estimator_entry("magic")


def test_every_property_with_a_flag_is_on_the_command_line(capsys):
    with pytest.raises(SystemExit):
        main(["render", "--help"])
    helptext = capsys.readouterr().out
    for p in settings.PROPERTIES:
        if p.flag:
            assert p.flag in helptext, p.flag


def test_estimators_command_lists_the_registry(capsys):
    assert main(["estimators"]) == 0
    out = capsys.readouterr().out
    for kind in estimator_registry.kinds():
        assert f"{kind.name}: {kind.doc}" in out


@pytest.mark.parametrize("key,value,allowed", [
    ("max_depth", 2 ** 32, "[-1, 4294967294]"), ("rr_depth", 2 ** 40, "[1, 4294967294]"),
    ("max_depth", "4294967296", "[-1, 4294967294]"), ("rr_depth", float("inf"), "[1, 4294967294]"),
    ("inner_samples", 2 ** 32 - 1, "[1, 4294967294]"),
])
def test_integer_settings_fit_the_kernels_uint32_depth(key, value, allowed):
    with pytest.raises(
        SettingsError, match=f"for '{key}': expected an integer in {re.escape(allowed)}"
    ):
        settings.parse({key: value})
    assert settings.parse({key: 2**32 - 2}).__getattribute__(
        key if key != "inner_samples" else "inner"
    )


def test_stylize_depth_is_capped():
    assert (
        settings.parse(
            {"stylize": "first_n_hits", "stylize_depth": settings.MAX_STYLIZE_DEPTH}
        ).stylize_depth
        == 16
    )
    with pytest.raises(
        SettingsError, match=r"for 'stylize_depth': expected an integer in \[1, 16\]"
    ):
        settings.parse({"stylize": "first_n_hits", "stylize_depth": 17})
    row = next(p for p in settings.PROPERTIES if p.name == "stylize_depth")
    assert "at most 16" in row.doc  # the generated settings table documents the cap


@pytest.mark.parametrize("value", [0, 1, "4"])
def test_samples_per_pass_is_refused(value):
    """Mitsuba would split each of styletrace's passes again and throw when they do not divide
    evenly."""
    with pytest.raises(SettingsError, match="for 'samples_per_pass': .*--pass-spp"):
        settings.parse({"samples_per_pass": value})


def test_emitter_sampling_is_a_setting():
    assert settings.parse({}).emitter_sampling == "auto"
    assert settings.parse({"emitter_sampling": "power"}).emitter_sampling == "power"
    assert settings.parse({"emitter_sampling": "spatial"}).emitter_sampling == "spatial"
    with pytest.raises(
        SettingsError,
        match="bad value 'loud' for 'emitter_sampling': expected one of auto, uniform, power, "
              "spatial",
    ):
        settings.parse({"emitter_sampling": "loud"})


def test_the_integrator_samples_emitters_the_way_it_is_told(monkeypatch):
    """The setting reaches the kernel's emitter sampler (power selection renders a different
    image)."""
    from styletrace.kernel import (
        render_context as module,  # where a render binds its emitter sampler
    )
    modes = []
    real = module.EmitterSampler
    monkeypatch.setattr(
        module, "EmitterSampler", lambda scene, mode: modes.append(mode) or real(scene, mode)
    )
    for mode in ("uniform", "power", "spatial"):
        styletrace.render("mixed", width=8, height=8, spp=1, inner=1, emitter_sampling=mode)
    assert modes == ["uniform", "power", "spatial"]
