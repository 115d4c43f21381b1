"""Cancel (Esc in Blender, `RenderEngine.test_break`) stops the render after the pass under way and leaves the
finished passes in the render result: the image equals a render of just those passes with the same seed."""
import time

import numpy as np

import scenes as S
from styletrace.blender import engine


def test_cancel_keeps_finished_passes(tmp_path, monkeypatch):
    S.room(64)
    stop_after = 2.0
    state = {}

    def test_break(self):  # the engine's stop_requested asks Blender's test_break
        # the user presses Esc 2 s after the render starts
        start = state.setdefault("start", time.perf_counter())
        return time.perf_counter() - start > stop_after

    monkeypatch.setattr(engine.StyletraceEngine, "stop_requested", test_break)
    t0 = time.perf_counter()
    out = S.styletrace(str(tmp_path / "cancelled.exr"), 1024, seed=5, pass_spp=4, style="identity", aovs=True)
    seconds = time.perf_counter() - t0
    done = engine.LAST["spp_done"]
    print(f"cancelled after {seconds:.1f} s with {done} of 1024 spp")
    assert engine.LAST["cancelled"] and 0 < done < 1024 and done % 4 == 0
    assert seconds < stop_after + 8  # export, the pass under way and writing the result
    assert np.isfinite(out["Variance"]).all() and "Bias" in out
    monkeypatch.undo()
    again = S.styletrace(str(tmp_path / "short.exr"), done, seed=5, pass_spp=4, style="identity", aovs=True)
    np.testing.assert_allclose(out["Combined"][..., :3], again["Combined"][..., :3], rtol=1e-6, atol=1e-7)
