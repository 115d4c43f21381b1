"""The engine reports progress after every pass (`RenderEngine.update_progress`, Blender's
progress bar): the fraction of samples done, pass by pass, up to 1; and a status line naming the
pass (`update_stats`)."""
import scenes as S

from styletrace.blender import engine


def test_progress_rises_pass_by_pass_to_one(tmp_path, monkeypatch):
    S.room(16)
    seen = []
    real = engine.StyletraceEngine.progress

    def progress(self, fraction, status):  # what the engine shows, passed on to Blender as before
        seen.append((fraction, status))
        real(self, fraction, status)

    monkeypatch.setattr(engine.StyletraceEngine, "progress", progress)
    S.styletrace(str(tmp_path / "p.exr"), 16, seed=1, pass_spp=4, style="identity",
                 sampler="independent")
    assert [f for f, _ in seen] == [0.25, 0.5, 0.75, 1.0]
    assert [s.split(",")[:2] for _, s in seen] == [
        [f"styletrace: pass {k}/4", f" {4 * k}/16 spp"] for k in range(1, 5)
    ]
    # the Owen-scrambled Sobol pattern (the default): F12's passes double from 4 (`f12.job`)
    seen.clear()
    S.styletrace(str(tmp_path / "q.exr"), 16, seed=1, pass_spp=4, style="identity",
                 sampler="owen_sobol")
    assert [f for f, _ in seen] == [0.25, 0.75, 1.0]
    assert [s.split(",")[:2] for _, s in seen] == [
        [f"styletrace: pass {k}/3", f" {n}/16 spp"] for k, n in ((1, 4), (2, 12), (3, 16))
    ]
