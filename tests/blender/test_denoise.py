"""F12 with Denoise on (render settings -> styletrace -> Denoise, `blender/denoising.py`).

- Expectation and image denoising give the command line's image: the scene exported to Mitsuba XML
  and rendered by `styletrace render FILE.xml --denoise ... --seed K --pass-spp N` (a textured
  floor: the guides' albedo carries the texture). The Noisy pass is the plain F12 render (Denoise
  off) with the same seed.
- With Record buffer on, Denoise expectation keeps the denoised buffer: a style change restyles it
  to what a fresh denoised F12 with the new value gives.
- Cancel keeps the finished passes, denoised: the image equals a denoised render of just those
  passes.
- Record buffer with Denoise image is refused in one line; error passes are off while denoising is
  on.
"""
import subprocess
import sys

import bpy
import numpy as np
import pytest
import scenes as S
from test_restyle import pixels
from test_xml import child_env

from styletrace.blender import engine, operators, restyle


@pytest.fixture(autouse=True)
def denoise_off():
    yield
    st = bpy.context.scene.styletrace
    st.denoise, st.record_buffer, st.aovs, st.firefly = "off", False, True, "auto"
    st.denoise_footprint = "pixel"


@pytest.mark.parametrize("method", ["expectation", "image"])
def test_f12_denoises_as_the_command_line(method, tmp_path):
    S.textured_plane(32)
    out = S.styletrace(
        str(tmp_path / "f12.exr"),
        8,
        seed=11,
        pass_spp=4,
        style="cel",
        inner_samples="4",
        denoise=method,
        aovs=True,
    )
    # no error pass: it would not be the denoised pixel's
    assert "Noisy" in out and "Variance" not in out
    f12, noisy = out["Combined"][..., :3], out["Noisy"][..., :3]
    # the plain F12 with the firefly control a denoised render gets at its default (docs/look.md;
    # error passes would turn it off: they describe the paper's estimator)
    plain = S.styletrace(
        str(tmp_path / "plain.exr"),
        8,
        seed=11,
        pass_spp=4,
        style="cel",
        inner_samples="4",
        denoise="off",
        firefly="on",
        aovs=False,
    )["Combined"][..., :3]
    np.testing.assert_allclose(noisy, plain, rtol=1e-5, atol=1e-6)
    assert np.abs(f12 - noisy).mean() > 1e-3  # denoising changed it
    xml = str(tmp_path / "scene.xml")
    bpy.context.scene.styletrace.denoise = method
    assert bpy.ops.styletrace.export_xml(filepath=xml) == {"FINISHED"}
    line = operators.command_line(xml, bpy.context.scene.styletrace)  # what the export reports
    assert line.endswith(f"--spp 8 --inner 4 --seed 11 --pass-spp 4 --denoise {method}"), line
    cli = str(tmp_path / "cli.exr")
    run = subprocess.run(
        [
            sys.executable,
            "-m",
            "styletrace",
            "render",
            xml,
            "--spp",
            "8",
            "--seed",
            "11",
            "--pass-spp",
            "4",
            "--denoise",
            method,
            "-q",
            "-o",
            cli,
        ],
        capture_output=True,
        text=True,
        env=child_env(),
        timeout=300,
    )
    assert run.returncode == 0, run.stderr
    import mitsuba as mi

    np.testing.assert_allclose(
        np.array(mi.Bitmap(cli), dtype=np.float32)[..., :3], f12, rtol=1e-5, atol=1e-5
    )


def test_the_image_denoisers_footprint_reaches_f12_and_the_command_line(tmp_path, monkeypatch):
    """Denoise image's input (`denoise_footprint`, docs/look.md): Pixel by default, Film as the
    switch back to the film's image; F12's finisher and the exported command line both carry it."""
    from styletrace.denoise import finishers
    props = type(bpy.context.scene.styletrace).bl_rna.properties
    assert props["denoise_footprint"].default == "pixel"
    seen, plan = [], finishers.plan

    def recorded(*args, **kw):
        runner = plan(*args, **kw)
        seen.append(runner.finisher.footprint)
        return runner

    monkeypatch.setattr(finishers, "plan", recorded)
    S.textured_plane(16)
    for footprint in ("pixel", "film"):
        S.styletrace(str(tmp_path / f"{footprint}.exr"), 2, style="identity",
                     denoise="image", denoise_footprint=footprint, aovs=False)
    assert seen == ["pixel", "film"]
    # the scene's settings now (textured_plane made a new scene)
    line = operators.command_line(str(tmp_path / "s.xml"), bpy.context.scene.styletrace)
    assert line.endswith("--denoise image --denoise-footprint film"), line


def test_the_denoise_default_is_every_front_ends():
    """Blender's Denoise starts at `pipeline.denoising.default_method()`, the default of the
    command line, the Python API and the preview (auto; the suite sets $STYLETRACE_DENOISE=off for
    its own renders: tests/conftest.py)."""
    from styletrace.pipeline.denoising import default_method
    prop = type(bpy.context.scene.styletrace).bl_rna.properties["denoise"]
    assert prop.default == default_method()
    assert {item.identifier for item in prop.enum_items} == {"auto", "off", "expectation", "image"}


def test_a_recorded_denoised_render_restyles_to_a_fresh_one(tmp_path):
    S.room(32)
    st = bpy.context.scene.styletrace
    S.styletrace(
        str(tmp_path / "recorded.exr"),
        8,
        seed=9,
        pass_spp=4,
        style="cel",
        inner_samples="4",
        record_buffer=True,
        denoise="expectation",
    )
    assert (
        restyle.buffer() is not None
        and restyle.buffer().header["denoise"]["method"] == "expectation"
    )
    st.params.cel__levels = "0.1,0.5"  # the update callback restyles
    restyled = pixels(bpy.data.images[restyle.IMAGE])
    fresh = S.styletrace(
        str(tmp_path / "fresh.exr"),
        8,
        seed=9,
        pass_spp=4,
        style="cel",
        inner_samples="4",
        record_buffer=False,
        denoise="expectation",
    )["Combined"][..., :3]
    np.testing.assert_allclose(restyled, fresh, rtol=1e-4, atol=1e-5)
    st.params.cel__levels = "0.4,0.95"


def test_cancel_denoises_the_finished_passes(tmp_path, monkeypatch):
    S.room(32)
    polls = {"n": 0}

    def test_break(self):
        polls["n"] += 1
        return polls["n"] >= 2  # Esc while the second pass is shown

    monkeypatch.setattr(engine.StyletraceEngine, "stop_requested", test_break)
    out = S.styletrace(
        str(tmp_path / "cancelled.exr"),
        64,
        seed=5,
        pass_spp=4,
        style="cel",
        inner_samples="4",
        denoise="expectation",
    )
    done = engine.LAST["spp_done"]
    assert engine.LAST["cancelled"] and done == 4 + 8  # F12's passes double (`f12.job`)
    monkeypatch.undo()
    again = S.styletrace(
        str(tmp_path / "short.exr"),
        done,
        seed=5,
        pass_spp=4,
        style="cel",
        inner_samples="4",
        denoise="expectation",
    )
    np.testing.assert_allclose(
        out["Combined"][..., :3], again["Combined"][..., :3], rtol=1e-5, atol=1e-6
    )
    np.testing.assert_allclose(out["Noisy"][..., :3], again["Noisy"][..., :3], rtol=1e-5, atol=1e-6)


def test_record_buffer_with_image_denoising_is_refused_in_one_line(tmp_path):
    S.room(16)
    with pytest.raises(RuntimeError) as info:
        S.styletrace(str(tmp_path / "x.exr"), 2, style="cel", record_buffer=True, denoise="image")
    message = str(info.value).strip()
    assert (
        message.startswith("Error:")
        and "Record buffer with Denoise 'image'" in message
        and "\n" not in message
    )
