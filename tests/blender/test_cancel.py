"""Cancel (Esc in Blender, `RenderEngine.test_break`) stops the render after the pass under way
and leaves the finished passes in the render result: the image equals a render of just those
passes with the same seed."""
import time

import numpy as np
import scenes as S

from styletrace.blender import engine

# the engine polls once a pass; the user presses Esc while the third pass is shown
PRESS_AT_POLL = 3


def test_cancel_keeps_finished_passes(tmp_path, monkeypatch):
    S.room(64)
    state = {"polls": 0, "pressed": None}

    def test_break(self):  # the engine's stop_requested asks Blender's test_break
        # pressed at a poll, not after a wall-clock delay: a fast machine finished all 1024 spp
        # inside 2 s
        state["polls"] += 1
        if state["polls"] >= PRESS_AT_POLL and state["pressed"] is None:
            state["pressed"] = time.perf_counter()
        return state["pressed"] is not None

    monkeypatch.setattr(engine.StyletraceEngine, "stop_requested", test_break)
    # independent samples: passes of 4 (with the default pattern they double: test_progress.py)
    out = S.styletrace(
        str(tmp_path / "cancelled.exr"), 1024, seed=5, pass_spp=4, style="identity", aovs=True,
        sampler="independent"
    )
    after_press = time.perf_counter() - state["pressed"]
    done = engine.LAST["spp_done"]
    print(f"returned {after_press:.2f} s after Esc with {done} of 1024 spp")
    # no further pass after Esc, just writing the result
    assert engine.LAST["cancelled"] and done == 4 * PRESS_AT_POLL
    assert np.isfinite(out["Variance"]).all() and "Bias" in out
    monkeypatch.undo()
    again = S.styletrace(
        str(tmp_path / "short.exr"), done, seed=5, pass_spp=4, style="identity", aovs=True,
        sampler="independent"
    )
    np.testing.assert_allclose(
        out["Combined"][..., :3], again["Combined"][..., :3], rtol=1e-6, atol=1e-7
    )
