"""The one progressive schedule (`progressive.schedule`, issue 44), driven step by step.

A machine is simulated: its clock stands still but for the work the schedule times, each pass
taking `pass_s` and each denoising `denoise_s` of simulated seconds (`Machine`). So what a test sees
never depends on how fast this machine is: a fast and a slow simulated machine show the same images
in the same order, and each image shown is compared with the final image: no further from it than
the raw pass it was made from, nor than the image shown before it. One scene is one where a quick
preview is further from the final image than the raw pass after every pass."""
import numpy as np
import pytest

from styletrace.denoise.finishers import Recording, plan
from styletrace.pipeline.denoising import Denoising
from styletrace.pipeline.job import python_job
from styletrace.progressive.rules import PREVIEW_K, PREVIEW_QUALITY
from styletrace.progressive.schedule import Schedule

pytest.importorskip("pyoidn", reason="the 'denoise' extra (pyoidn) is not installed")


class Machine:
    """Simulated time: `clock()` reads it; the runners it makes advance it by `pass_s` per pass
    and `denoise_s` per denoising (quick preview or finisher), nothing else.

    Args:
        pass_s, denoise_s: simulated seconds of a pass and of a denoising.
    """

    def __init__(self, pass_s: float, denoise_s: float):
        self.pass_s, self.denoise_s = pass_s, denoise_s
        self.now = 0.0
        self.raws: dict[int, np.ndarray] = {}  # each pass's raw image, by camera samples done

    def clock(self) -> float:
        return self.now

    def runner(self, job, recording=Recording()):
        """The job's run, timed on this machine: its passes (each raw image kept) and its
        denoisings advance the clock."""
        r = plan(job, recording=recording)
        passes, finish = r.passes, r.finish

        def timed_passes(*args, **kw):
            for prog in passes(*args, **kw):
                self.now += self.pass_s
                self.raws[prog.spp_done] = np.array(prog.image[..., :3])
                yield prog

        def timed(fn):
            def call(*args, **kw):
                self.now += self.denoise_s
                return fn(*args, **kw)
            return call

        r.passes, r.finish = timed_passes, timed(finish)
        job_of = getattr(r.finisher, "job", None)
        if job_of is not None:
            # the finisher's job exists after the run's checks, which `plan` made
            job_of.preview = timed(job_of.preview)
        return r


def run(job, machine: Machine, draft: bool = True) -> tuple[Schedule, list]:
    """Drive a schedule of `job` on `machine` step by step to its end.

    Returns:
        (the schedule, every frame in the order shown).
    """
    draft_job = job.with_(draft=True, denoising=Denoising("auto", quality="balanced"))
    s = Schedule(lambda: machine.runner(job), (lambda: machine.runner(draft_job)) if draft else
    None,
                 clock=machine.clock)
    frames = []
    while not s.done:
        frame = s.step()
        if frame is not None:
            frames.append(frame)
    assert s.error is None and frames == s.frames
    return s, frames


def mse(a, b) -> float:
    return float(np.mean((np.asarray(a, np.float64) - b) ** 2))


def assert_each_closer(frames, machine: Machine, final: np.ndarray) -> None:
    """Every frame is at least as close to `final` as the raw image of the passes it was made
    from (`machine.raws`), and no further from it than the frame before."""
    errors = [mse(f.image, final) for f in frames]
    for f, e in zip(frames, errors):
        raw = mse(machine.raws[f.spp], final)
        print(f"{f.label}: {e:.3e} from the final image, the raw pass {raw:.3e}")
        assert e <= raw
    assert errors == sorted(errors, reverse=True)


def cel_job(samples=32, size=48):
    """Cel on the Cornell box: passes of one camera sample of 4 children (the budget's)."""
    return python_job("cornell-box", style="cel", width=size, height=size, samples=samples, seed=7,
                      pass_spp=1, denoising=Denoising("expectation"))


def test_a_fast_and_a_slow_machine_show_the_same_images_in_the_same_order():
    """The decisions read only ratios of the times (`rules.denoise_now`): a machine ten times
    slower shows the same images, bit for bit, in the same order; a denoising three times as long
    as a pass leaves passes without a new image (the test would not notice a clock that changed
    nothing)."""
    shown = []
    for scale in (0.1, 1.0):
        machine = Machine(pass_s=1.0 * scale, denoise_s=3.0 * scale)
        s, frames = run(cel_job(), machine)
        shown.append(frames)
        print(scale, [(f.kind, f.label, f"{f.seconds:.1f} s") for f in frames])
    fast, slow = shown
    assert [(f.kind, f.label, f.spp) for f in fast] == [(f.kind, f.label, f.spp) for f in slow]
    for a, b in zip(fast, slow):
        np.testing.assert_array_equal(a.image, b.image)
    kinds = [f.kind for f in fast]
    assert kinds[0] == "draft" and kinds[-1] == "final" and "preview" in kinds
    previews = [f for f in fast if f.kind in ("preview", "final")]
    assert len(previews) < 8  # 8 passes: some kept the image on screen
    assert [f.seconds for f in slow] == pytest.approx([10 * f.seconds for f in fast])


@pytest.mark.parametrize("pass_s, denoise_s", [(1.0, 0.0), (1.0, 3.0)])
def test_each_image_is_no_further_from_the_final_than_its_raw_pass_or_the_one_before(
    pass_s, denoise_s
):
    """Cel on the Cornell box, denoised at every pass (an instant denoiser) or after some: every
    full-size image shown is at least as close to the final image as the raw image of the passes
    it was made from, and no further from it than the image shown before it."""
    machine = Machine(pass_s, denoise_s)
    _, frames = run(cel_job(), machine)
    full = [f for f in frames if f.kind != "draft"]
    assert_each_closer(full, machine, full[-1].image)


def test_where_a_quick_preview_loses_to_the_raw_pass_the_renders_own_denoiser_is_shown():
    """The Cornell box at 32 x 32, identity with 4 children, passes of 16 camera samples: a quick
    preview (`rules.PREVIEW_K` points, OIDN `rules.PREVIEW_QUALITY`) is further from the final
    image than the raw pass after every pass (its bias at the light's bright edges stays as the
    noise falls: measured 2.8e-2 against 8.5e-3 to 2.0e-3). The schedule, denoising at every pass,
    shows the render's own denoiser instead: each image at least as close as the raw pass, and
    closer than the one before."""
    job = python_job("cornell-box", style="identity", inner=4, width=32, height=32, samples=256,
                     seed=3, pass_spp=16, denoising=Denoising("expectation"))
    # the premise: a quick preview of each pass loses to its raw image
    r = plan(job)
    quick, raws = [], []
    for prog in r.passes():
        quick.append(r.finisher.job.preview(PREVIEW_K, PREVIEW_QUALITY)[0])
        raws.append(np.array(prog.image[..., :3]))
    final = r.finish(prog)
    losses = [mse(q, final) > mse(raw, final) for q, raw in zip(quick, raws)]
    assert all(losses), losses
    machine = Machine(pass_s=1.0, denoise_s=0.0)
    _, frames = run(job, machine, draft=False)
    np.testing.assert_array_equal(frames[-1].image, final)  # the same run, the same final
    assert [f.kind for f in frames] == ["preview"] * 2 + ["final"]  # 1, 2 and 4 passes
    assert not any(f.label.endswith("(preview)") for f in frames)  # no quick preview
    assert_each_closer(frames, machine, final)


def test_a_quick_preview_is_shown_only_over_one_camera_sample():
    """The first denoised image of passes of one camera sample is a quick preview (the fast first
    clean image); every later one is the render's own denoiser, whose images converge to the
    final one, each from twice the camera samples of the one before (`rules.GROWTH`)."""
    _, frames = run(cel_job(samples=64), Machine(1.0, 0.0))
    labels = [f.label for f in frames]
    assert labels[0].startswith("draft, denoised") and frames[0].spp == 1
    assert labels[1] == "pass 1/16, 1 spp, denoised (preview)"
    assert labels[2:] == ["pass 2/16, 2 spp, denoised", "pass 4/16, 4 spp, denoised",
                          "pass 8/16, 8 spp, denoised", "pass 16/16, 16 spp, denoised"]


def test_the_draft_is_the_budgets_smaller_request():
    """The draft asks the same resolve for its own request (`Job.draft`): one camera sample of
    the children the render's split gives."""
    job = cel_job()
    whole = plan(job).resolved
    draft = plan(job.with_(draft=True)).resolved
    assert (draft.spp, draft.budget.children) == (1, whole.budget.children)
    _, frames = run(job, Machine(1.0, 0.0))
    assert frames[0].kind == "draft" and frames[0].children == int(whole.budget.children[0])


def test_a_stopped_schedule_ends_after_its_step():
    machine = Machine(1.0, 0.0)
    s = Schedule(lambda: machine.runner(cel_job()), clock=machine.clock)
    first = s.step()
    assert first is not None and first.label == "pass 1/8, 1 spp, denoised (preview)"
    s.stop()
    s.run()  # returns at once: stopped
    assert s.done and len(s.frames) == 1
