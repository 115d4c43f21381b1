"""Blender's Samples (issue 36): paths per pixel, split into camera samples x children by the
pipeline's rule (`pipeline.budget`), as the Python API and the command line split the same scene's
samples; Camera samples and Inner samples, where given, win; the export reports the counts F12
uses."""
import bpy
import scenes as S

from styletrace.blender import engine, f12, operators, panels
from styletrace.pipeline.job import python_job
from styletrace.pipeline.resolve import resolve


def planned(sc, st, **kw):
    """(spp, n) the Python API's render of `sc` with F12's denoise setting runs."""
    from styletrace.pipeline.denoising import Denoising
    r = resolve(python_job(sc, style="cel", denoising=Denoising(st.denoise), **kw), scene=sc)
    return r.spp, int(r.integrator.settings.slot.n(0))


def split_of(st):
    """(spp, n) of F12's run with the settings `st`, and the loaded scene (the resolved job of the
    runner F12 builds: nothing renders)."""
    sc = f12.scene(bpy.context.evaluated_depsgraph_get(), st)
    r = f12.run_f12(sc, st, aovs=False).resolved
    return (r.spp, int(r.integrator.settings.slot.n(0))), sc


def test_samples_split_as_every_front_end_splits_them(tmp_path):
    S.room(16)
    st = bpy.context.scene.styletrace
    st.style, st.denoise = "cel", "expectation"
    assert (st.samples, st.spp, st.inner_samples) == (16, 0, "")  # Samples 16, the rest auto
    got, sc = split_of(st)
    assert got == (4, 4)
    # the exported sampler counts Samples; the Python API's split of the same scene is F12's
    from styletrace.scene.loading import scene_spp
    assert scene_spp(sc) == 16
    assert planned(sc, st) == got
    st.samples = 64
    got, sc = split_of(st)
    assert got == (16, 4) and scene_spp(sc) == 64
    assert planned(sc, st, samples=64) == got
    # not denoised: g meets each camera sample's mean, and cel keeps its own 16 children
    st.denoise = "off"
    got, sc = split_of(st)
    assert got == (4, 16) and planned(sc, st, samples=64) == got
    line = operators.command_line("s.xml", st)
    assert line.startswith("styletrace render s.xml --samples 64 --seed 0 --pass-spp 1"), line
    # F12 renders the split: its passes' spp (one pass of 1 camera sample of 16 children)
    st.samples = 16
    S.styletrace(str(tmp_path / "f12.exr"), 0, pass_spp=4, style="cel", aovs=False)
    assert engine.LAST["spp_total"] == 1 and engine.LAST["spp_done"] == 1


def test_camera_and_inner_samples_win():
    S.room(16)
    st = bpy.context.scene.styletrace
    st.style, st.denoise, st.samples = "cel", "off", 64
    st.spp = 4  # Camera samples alone: Samples / 4 children each
    assert split_of(st)[0] == (4, 16)
    assert "--samples 64 --spp 4 --seed" in operators.command_line("s.xml", st)
    st.samples = 16
    assert split_of(st)[0] == (4, 4)
    st.spp, st.denoise = 0, "expectation"
    assert split_of(st)[0] == (4, 4)
    st.spp, st.inner_samples = 0, "8"  # Inner samples alone: Samples / 8 camera samples
    assert split_of(st)[0] == (2, 8)
    assert "--samples 16 --inner 8 --seed" in operators.command_line("s.xml", st)
    assert panels.samples_used(st)
    st.spp = 3  # both: they set the cost, Samples is not used (3 x 8 != 16 is no refusal)
    assert split_of(st)[0] == (3, 8) and not panels.samples_used(st)
    line = operators.command_line("s.xml", st)
    assert " --spp 3 --inner 8 --seed" in line and "--samples" not in line, line


def test_the_advanced_sub_panel_holds_the_split():
    S.reset(16)
    st = bpy.context.scene.styletrace
    main = [name for _, name in panels.layout_rows(st)]
    assert "samples" in main and not {"spp", "inner_samples", "pass_spp"} & set(main)
    assert [name for _, name in panels.layout_rows(st, advanced=True)] == [
        "spp", "inner_samples", "pass_spp", "sampler"]
    rna = st.bl_rna.properties
    assert (rna["samples"].name, rna["samples"].default, rna["samples"].hard_min) == (
        "Samples", 16, 1)
    assert (rna["spp"].name, rna["spp"].default, rna["spp"].hard_min) == ("Camera samples", 0, 0)
    assert panels.dump(st, advanced=True)[0].startswith("Camera samples           0")


def test_the_viewport_renders_f12s_split_and_its_draft_the_budgets_smaller_request():
    """Rendered shading plans F12's job (`f12.job`): its passes' split is F12's, the one
    function's answer; its draft is that function asked one camera sample of those children."""
    from styletrace.blender import camera
    from styletrace.blender.viewport import Viewport
    S.room(16)
    st = bpy.context.scene.styletrace
    st.style, st.denoise, st.samples = "cel", "expectation", 64
    f12_split, _ = split_of(st)
    vp = Viewport(start=False, clock=lambda: 0.0)
    dg = bpy.context.evaluated_depsgraph_get()
    vp.set_sensor(camera.sensor(dg.scene_eval, st.samples))
    vp.update(dg, st)
    s = vp.session
    draft = s.plan_draft().resolved
    whole = s.plan().resolved
    vp.close()
    assert (whole.spp, int(whole.integrator.settings.slot.n(0))) == f12_split == (16, 4)
    assert (draft.spp, draft.budget.children) == (1, whole.budget.children)
