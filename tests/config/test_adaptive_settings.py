"""Adaptive inner counts in the settings: `n0:n_max` parsed once, refused where a guarantee would
be lost."""
import pytest

import styletrace
from styletrace.config import estimator_registry, settings
from styletrace.config.settings import AdaptiveCount
from styletrace.errors import SettingsError
from styletrace.frontends.cli import main

styletrace.init()


@pytest.mark.parametrize("raw,expected", [("4:64", ((4, 64),)), ("4:64,2:8", ((4, 64), (2, 8))),
                                          (" 3 : 3 ", ((3, 3),)), ("8,2:8", (8, (2, 8)))])
def test_spellings(raw, expected):
    got = settings.parse_inner(raw, 1)
    shape = tuple((int(n), n.n_max) if isinstance(n, AdaptiveCount) else n for n in got)
    assert shape == expected
    assert settings.adaptive(got)
    assert all(int(n) == (e[0] if isinstance(e, tuple) else e) for n, e in zip(got, expected))


def test_a_fixed_count_stays_a_plain_int():
    got = settings.parse_inner("8,4", 1)
    assert got == (8, 4) and not settings.adaptive(got) and all(type(n) is int for n in got)


@pytest.mark.parametrize("raw,why", [("64:4", "n0 <= n_max"), ("0:4", r"\[1, "), ("4:x", r"\[1, "),
                                     ("4:", r"\[1, ")])
def test_bad_adaptive_counts(raw, why):
    with pytest.raises(SettingsError, match=why) as e:
        settings.parse({"style": "cel", "inner_samples": raw})
    assert "\n" not in str(e.value)


@pytest.mark.parametrize(
    "style,name",
    [
        ("gamma", "series"),
        ("gamma", "series_single"),
        ("tie_dye", "ustat"),
        ("tie_dye", "naive"),
        ("gamma", "telescoping"),
        ("contrast", "affine"),
    ],
)
def test_unbiased_estimators_refuse_adaptive_counts(style, name):
    with pytest.raises(
        SettingsError, match="adaptive counts n0:n_max stop on the data.*estimator direct"
    ) as e:
        settings.parse({"style": style, "estimator": name, "inner_samples": "4:64"})
    assert "\n" not in str(e.value)
    # a fixed count is fine
    settings.parse({"style": style, "estimator": name, "inner_samples": "4"})


def test_per_sample_baselines_refuse_adaptive_counts():
    with pytest.raises(SettingsError, match="averages g over its children"):
        settings.parse({"style": "acp", "inner_samples": "4:64"})


def test_adaptive_properties():
    s = settings.parse({"style": "cel", "inner_samples": "4:64"})
    assert (s.adaptive_z, s.adaptive_bias, s.aovs) == (2.0, 2e-3, False)
    s = settings.parse(
        {
            "style": "cel",
            "inner_samples": "4:64",
            "adaptive_z": "3",
            "adaptive_bias": 1e-4,
            "aovs": "true",
        }
    )
    assert (s.adaptive_z, s.adaptive_bias, s.aovs) == (3.0, 1e-4, True)
    for key, bad in (
        ("adaptive_z", 0),
        ("adaptive_z", "nan"),
        ("adaptive_bias", -1),
        ("aovs", "maybe"),
    ):
        with pytest.raises(SettingsError, match=f"bad value .* for '{key}'"):
            settings.parse({"style": "cel", key: bad})


def test_aovs_need_direct_application():
    with pytest.raises(SettingsError, match="'aovs' with estimator 'series'.*use estimator=direct"):
        settings.parse({"style": "gamma", "estimator": "series", "aovs": True})


def test_the_builder_picks_adaptive_direct_only_where_asked():
    from styletrace.estimators import AdaptiveDirect, Direct
    fixed = settings.parse({"style": "cel", "inner_samples": "8"})
    est = estimator_registry.make_estimator(fixed.slot, 0, None, fixed)
    assert type(est.inner) is Direct
    ad = settings.parse({"style": "color_map", "inner_samples": "4:64", "adaptive_z": 3})
    est = estimator_registry.make_estimator(ad.slot, 0, None, ad)
    assert type(est.inner) is AdaptiveDirect and (est.inner.n0, est.inner.n_max, est.inner.z) == (
        4,
        64,
        3.0,
    )
    # a per-level count: the second level is fixed
    deep = settings.parse({"style": "cel", "inner_samples": "4:64,2", "stylize": "first_n_hits",
                           "stylize_depth": 2})
    assert type(estimator_registry.make_estimator(deep.slot, 1, None, deep).inner) is Direct


def test_command_line_refusal_is_one_line(capsys):
    assert (
        main(
            [
                "render",
                "--style",
                "gamma",
                "--estimator",
                "series",
                "--inner",
                "4:64",
                "-o",
                "x.exr",
            ]
        )
        == 2
    )
    err = capsys.readouterr().err.strip()
    assert err.count("\n") == 0 and "adaptive counts n0:n_max" in err
