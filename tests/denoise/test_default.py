"""What a render does at defaults (`denoise.default`): auto denoises the expectation where it
applies, with the firefly control and an auto spp within the buffer's cap; where it cannot, it
says why in one line and renders as `denoise="off"` does; `off` is the pipeline's render of the
paper's estimators, bit for bit."""
import os
import subprocess
import sys
import warnings

import numpy as np
import pytest
from conftest import child_env  # noqa: F401  (tests/conftest.py: the source tree first on PYTHONPATH)

import styletrace
from styletrace.denoise import NotDenoised
from styletrace.denoise.default import FIREFLY_K, choose
from styletrace.pipeline.job import python_job
from styletrace.pipeline.resolve import resolve

ROOT = os.path.join(os.path.dirname(__file__), "..", "..")
SMALL = dict(width=24, height=24, seed=3)


@pytest.fixture
def auto(monkeypatch):
    """Every front end's default, as a user has it (the suite sets $STYLETRACE_DENOISE=off)."""
    monkeypatch.delenv("STYLETRACE_DENOISE", raising=False)


def test_auto_plans_expectation_with_the_firefly_control_and_the_budget_spent(auto):
    plan = choose(resolve(python_job("cornell-box", style="cel", **SMALL)))
    assert plan.method == "expectation" and plan.note == ""
    s = plan.resolved.integrator.settings
    assert s.firefly == FIREFLY_K and s.firefly_floor > 0
    # the built-in scene's 16 samples: 4 camera samples of 4 children (pipeline.budget)
    assert plan.resolved.spp == 4 and int(s.slot.n(0)) == 4
    assert "firefly=4" in plan.resolved.auto
    assert "samples=16: spp=4 x 4 children" in plan.resolved.auto
    # a given spp is the user's: kept
    assert choose(resolve(python_job("cornell-box", style="cel", spp=8, **SMALL))).resolved.spp == 8


def test_the_default_is_auto_and_equals_expectation_with_the_values_it_pins(auto):
    image = styletrace.render("cornell-box", style="cel", **SMALL)
    plan = choose(resolve(python_job("cornell-box", style="cel", **SMALL)))
    s = plan.resolved.integrator.settings
    explicit = styletrace.render(
        "cornell-box",
        style="cel",
        denoise="expectation",
        spp=plan.resolved.spp,
        inner=int(s.slot.n(0)),
        firefly=s.firefly,
        firefly_floor=s.firefly_floor,
        **SMALL,
    )
    assert np.array_equal(image, explicit)
    off = styletrace.render("cornell-box", style="cel", denoise="off", **SMALL)
    assert not np.array_equal(image, off)


def test_what_auto_cannot_denoise_is_said_in_one_line_and_rendered_as_off(auto):
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        image = styletrace.render("cornell-box", style="cel", lines=True, inner=2, spp=2, **SMALL)
    notes = [w for w in caught if issubclass(w.category, NotDenoised)]
    assert len(notes) == 1 and "\n" not in str(notes[0].message), [str(w.message) for w in caught]
    assert str(notes[0].message).startswith("not denoised: feature lines")
    off = styletrace.render(
        "cornell-box", style="cel", lines=True, inner=2, spp=2, denoise="off", **SMALL
    )
    assert np.array_equal(image, off)


def test_the_command_line_says_why_it_did_not_denoise(tmp_path):
    env = {k: v for k, v in child_env().items() if k != "STYLETRACE_DENOISE"}
    out = tmp_path / "lines.exr"
    r = subprocess.run(
        [
            sys.executable,
            "-m",
            "styletrace",
            "render",
            "--lines",
            "--width",
            "16",
            "--height",
            "16",
            "--spp",
            "2",
            "--inner",
            "2",
            "-o",
            str(out),
        ],
        capture_output=True,
        text=True,
        env=env,
        timeout=300,
    )
    assert r.returncode == 0, r.stderr
    notes = [line for line in r.stderr.splitlines() if "not denoised" in line]
    assert notes == [
        "styletrace: not denoised: feature lines: lines replace radiance inside the estimate; use "
        "--denoise image"
    ], r.stderr


def test_a_bad_default_in_the_environment_is_refused_in_one_line(monkeypatch):
    monkeypatch.setenv("STYLETRACE_DENOISE", "always")
    with pytest.raises(
        styletrace.errors.UsageError, match=r"bad value 'always' for \$STYLETRACE_DENOISE"
    ):
        styletrace.render("cornell-box", style="cel", **SMALL)


#: configurations of benchmarks/bit_identity.py rendered through `styletrace.render(denoise="off")`
OFF_CONFIGS = [
    "first_hit_cel",
    "affine_contrast",
    "series_gamma",
    "naive_tie_dye",
    "hide_emitters_depth3",
]


@pytest.mark.parametrize("name", OFF_CONFIGS)
def test_off_is_the_pass_loop_of_the_papers_estimators_bit_for_bit(name):
    """`denoise="off"` draws exactly what the pass loop draws with a prebuilt integrator of the
    same values: the seam benchmarks/bit_identity.py hashes across refactorings (its digests
    depend on the CPU's instruction set, so they are compared there, on one machine, not here).
    Its cel configurations pin the levels cel had by default before the look defaults; the
    firefly control is off unless asked for."""
    sys.path.insert(0, os.path.join(ROOT, "benchmarks"))
    try:
        import bit_identity
    finally:
        sys.path.pop(0)
    from styletrace.frontends import api
    scene, spp, values = bit_identity.CONFIGS[name]
    image = styletrace.render(
        scene,
        spp=spp,
        seed=7,
        width=bit_identity.RES,
        height=bit_identity.RES,
        denoise="off",
        **values,
    )
    seam = list(api.passes(api.load_scene(scene, bit_identity.RES, bit_identity.RES),
                           api.make_integrator_from(values), spp, seed=7))[-1].image
    assert bit_identity.digest(image) == bit_identity.digest(seam)
    assert api.make_integrator_from(values).settings.firefly is None


@pytest.mark.parametrize("style,inner", [("identity", None), ("gooch", None), ("acp", 4)])
def test_auto_denoises_the_image_where_the_expectation_adds_nothing_or_is_refused(
    auto, style, inner
):
    """One child or none (identity, gooch: g of the denoised mean is the denoised image), or g
    applied to every child (acp, which the expectation's denoiser refuses): auto denoises the
    image."""
    plan = choose(resolve(python_job("cornell-box", style=style, inner=inner, **SMALL)))
    assert plan.method == "image" and plan.note == ""
    image = styletrace.render("cornell-box", style=style, inner=inner, **SMALL)
    assert np.array_equal(
        image, styletrace.render("cornell-box", style=style, inner=inner, denoise="image", **SMALL)
    )


def test_a_given_spp_over_the_buffers_cap_denoises_the_image(auto, monkeypatch):
    from styletrace.lookdev import buffer
    monkeypatch.setattr(buffer, "MAX_SAMPLES", 24 * 24 * 3)
    assert choose(resolve(python_job("cornell-box", style="cel", spp=4, **SMALL))).method == "image"
    # without a given spp the budget is spent within the cap instead: 64 samples would be 16 x 4,
    # the cap allows 3 camera samples, so each takes ceil(64 / 3) = 22 children
    plan = choose(resolve(python_job("cornell-box", style="cel", samples=64, **SMALL)))
    assert plan.method == "expectation" and plan.resolved.spp == 3
    assert int(plan.resolved.integrator.settings.slot.n(0)) == 22
    assert "samples=64: spp=3 x 22 children" in plan.resolved.auto
    assert "spp=4" not in plan.resolved.auto
