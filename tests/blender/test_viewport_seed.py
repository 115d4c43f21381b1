"""A change of seed in Rendered shading compiles no kernel (issue 47): the seed reaches the kernels
as data, never as a literal of their code. After a session at one seed has run to its end (draft,
passes, denoising, restyle warm-up), a session at another seed launches only kernels this process
has compiled already: Dr.Jit's kernel history reports every JIT launch as an in-memory cache hit,
none compiled or loaded from the disk cache. Sessions at more seeds check it is not a chance of
one value. Dr.Jit compiles every live Mitsuba object of a class into a kernel's calls, so the
garbage of earlier tests and sessions, freed by the collector at its own time, would change the
kernels' code mid-test (docs/design/viewport.md, "Garbage and Dr.Jit's registry"): the garbage
is collected before each session, as the viewport collects it between sessions, and the first
new seed settles the registry."""
import gc

import bpy
import drjit as dr
import scenes as S

from styletrace.blender import camera
from styletrace.blender.viewport import Viewport


def session(vp, st):
    vp.update(bpy.context.evaluated_depsgraph_get(), st)
    s = vp.session
    while not s.done:
        s.schedule.step()
    assert s.error is None
    return s.latest()[0]


def test_a_seed_change_compiles_no_kernel():
    S.interior(48)
    st = bpy.context.scene.styletrace
    st.style, st.seed, st.denoise = "cel", 0, "auto"
    vp = Viewport(start=False, clock=lambda: 0.0)  # a clock that stands still: the same
    # schedule (passes, denoised previews) whatever this machine's speed
    vp.set_sensor(camera.sensor(bpy.context.evaluated_depsgraph_get().scene_eval, st.samples))
    first = session(vp, st)
    dr.set_flag(dr.JitFlag.KernelHistory, True)
    try:
        for k, seed in enumerate((1, 7, 99, 123456)):
            gc.collect()
            dr.kernel_history()  # reading it empties it
            st.seed = seed
            image = session(vp, st)
            launches = [k for k in dr.kernel_history() if "cache_hit" in k]
            assert launches, "no JIT kernel was launched: the check could not see a compile"
            compiled = [(k["hash"], k["operation_count"], k["size"], k["input_count"])
                        for k in launches if not k["cache_hit"] or k["cache_disk"]]
            assert k == 0 or not compiled, (seed, compiled)
            assert (image != first).any()  # another seed: other samples
    finally:
        dr.set_flag(dr.JitFlag.KernelHistory, False)
        vp.close()
