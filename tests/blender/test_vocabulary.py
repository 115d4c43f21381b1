"""Blender's labels say `samples` for paths per pixel only (issue 44): the render settings' and the
material's fields, their descriptions, and the errors F12 shows name Blender's own fields. The
command line, Python and the preview: tests/test_vocabulary.py."""
import bpy
import pytest
import scenes as S
from vocabulary import unqualified_counts

from styletrace.blender import f12
from styletrace.errors import UsageError

#: Blender's labels that hold "samples", and what each counts
LABELS = {"Samples": "paths per pixel", "Camera samples": "camera samples per pixel",
          "Inner samples": None, "Camera samples per pass": "camera samples per pixel in one pass"}


def fields():
    """(owner, property) of every styletrace setting on a scene and on a material."""
    S.reset(8)
    owners = [bpy.context.scene.styletrace, bpy.data.materials.new("m").styletrace]
    for owner in owners:
        for prop in owner.bl_rna.properties:
            if prop.identifier != "rna_type":
                yield owner, prop


def test_the_fields_say_samples_for_paths_per_pixel_only():
    seen = set()
    for _, prop in fields():
        assert not unqualified_counts(prop.description), (prop.name, prop.description)
        if "sample" in prop.name.lower():
            assert prop.name in LABELS, prop.name
            seen.add(prop.name)
            want = LABELS[prop.name]
            assert want is None or prop.description.startswith(want), (prop.name,
                                                                     prop.description)
    assert {"Samples", "Camera samples", "Camera samples per pass"} <= seen


def test_f12s_refusal_names_blenders_fields():
    S.room(8)
    st = bpy.context.scene.styletrace
    st.style, st.samples, st.spp, st.inner_samples = "cel", 64, 4, "8"
    sc = f12.scene(bpy.context.evaluated_depsgraph_get(), st)
    # Camera samples and Inner samples both given set the cost; Samples is not used then
    assert f12.run_f12(sc, st, aovs=False).resolved.spp == 4
    from styletrace.pipeline.resolve import resolve
    from styletrace.pipeline.terms import BLENDER
    job = f12.job(sc, f12.integrator(st, aovs=False), st).with_(samples=64)
    assert job.terms is BLENDER
    with pytest.raises(UsageError, match=r"^'Samples' 64 with 'Camera samples' 4 and 'Inner "
                                         r"samples' 8 \(32 paths per pixel\)"):
        resolve(job, scene=sc)
