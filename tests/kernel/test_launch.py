"""Renders leave the scene's sample count as it was (`kernel.launch.render_pass`).

Mitsuba's render loop sets the sensor's sampler to each launch's sample count. A scene object
rendered in passes of one camera sample then said its file asked for one, and the next render of
the same object took another default budget (`samples`: the scene's count). Checked through the
Python API on a loaded scene: its count after renders of several splits, and the same split twice.
"""
from styletrace.frontends import api
from styletrace.pipeline.job import python_job
from styletrace.pipeline.resolve import resolve
from styletrace.scene.loading import scene_spp


def test_a_scene_keeps_its_sample_count_across_renders():
    scene = api.load_scene("cornell-box", 8, 8)
    assert scene_spp(scene) == 16
    first = resolve(python_job(scene, style="cel"), scene=scene)
    api.render(scene, style="cel", pass_spp=1, denoise="off")  # passes of one camera sample
    api.render(scene, style="identity", spp=3, denoise="off")
    assert scene_spp(scene) == 16
    again = resolve(python_job(scene, style="cel"), scene=scene)
    assert (again.spp, again.budget.children) == (first.spp, first.budget.children)
