"""One progressive schedule for every interactive view: draft, passes, previews, final, warm-up.

    s = Schedule(lambda: plan(job, scene=sc), draft=lambda: plan(job.with_(draft=True), ...))
    while not s.done:
        frame = s.step()        # one step under `s.turns`; None where the image on screen stays
    s.start()                   # or: the same steps in a thread (Blender's viewport, the preview)

A schedule renders a job's passes (`denoise.finishers.plan`, the run every front end makes) and
decides which images a view shows, in this order:

0. an adapter's **first** step (where given: the viewport shows the image of the view before,
   carried to the new one, `blender.viewport_carry`);
1. the **draft** (where given): one camera sample of the render's children, at the draft's size
   (`rules.draft_size`), denoised as auto would (`Job.draft`: the budget's own smaller request);
2. after each **pass**: undenoised, the raw image of the passes so far; denoised, where
   `rules.denoise_now` says so and the passes hold `rules.GROWTH` times the camera samples of the
   denoised image on screen (`rules.worth_showing`), a denoised image of the passes so far: a quick
   preview (`ExpectationJob.preview`, `rules.PREVIEW_K` points, OIDN `rules.PREVIEW_QUALITY`) only
   while the raw image holds one camera sample per pixel (`rules.quick_serves`: a quick preview's
   error is below a single camera sample's, not below that of several), else the render's own
   denoiser on the passes so far, which converges to the final image;
3. the **final** image, the render's own finisher (what F12 and the command line write);
4. a **warm-up** (`warm`, an adapter's: its restyle kernels compiled before a drag needs them).

Every step runs under one lock (`turns`, which lets waiting restyles go first), and times itself on
the schedule's `clock`; the decisions read only ratios of those times (`rules.denoise_now`), so a
fast and a slow clock show the same images in the same order. Each image is a `Frame`; the
adapters (`blender.viewport`, `preview.session`) show or restyle them. Design:
docs/design/progressive_schedule.md.
"""
from __future__ import annotations

import threading
import time
from dataclasses import dataclass
from typing import Any, Callable, Iterator

import numpy as np

from styletrace.denoise.finishers import Denoised, Expectation
from styletrace.pipeline.runner import Runner
from styletrace.progressive.rules import (
    PREVIEW_K,
    PREVIEW_QUALITY,
    denoise_now,
    quick_serves,
    worth_showing,
)


@dataclass(frozen=True)
class Frame:
    """An image the schedule shows.

    Args:
        kind: "draft", "pass" (raw), "preview" (denoised before the last pass) or "final".
        label: how a view names it, e.g. "pass 1/4, 1 spp, denoised (preview)".
        image: H x W x 3 float32, linear: the render's own style.
        buffer: the expectation buffer that restyles to `image` (through `denoiser`), or None.
        spp: camera samples per pixel in it. children: children per camera sample.
        version: its number, from 1, in the order shown. seconds: on the schedule's clock, from
            its start.
        denoiser: what turns a restyle of `buffer` into a shown image (the image denoiser's OIDN
            with this frame's guides), or None: the restyle is the image.
    """
    kind: str
    label: str
    image: np.ndarray
    buffer: Any
    spp: int
    children: int
    version: int
    seconds: float
    denoiser: Callable[[np.ndarray], np.ndarray] | None = None


class Turns:
    """The schedule's one lock, held by each step and by each restyle of its images; restyles
    that wait for it go before the schedule's next step (a step holds it for up to seconds, a
    restyle for milliseconds, and a plain lock is not fair).

    Args:
        lock: the lock to share (Blender's viewport: one for every view's schedule), or None: a
            new one.
    """

    def __init__(self, lock: Any = None):
        self.lock = lock if lock is not None else threading.Lock()
        self._waiting = 0
        self._count = threading.Lock()

    def acquire(self, wait: bool = True) -> bool:
        """Take the lock for a restyle: waiting, ahead of the schedule's next step, or (`wait`
        False) only if it is free. `release` gives it back.

        Returns:
            Whether the lock was taken.
        """
        if not wait:
            return self.lock.acquire(blocking=False)
        with self._count:
            self._waiting += 1
        try:
            self.lock.acquire()
        finally:
            with self._count:
                self._waiting -= 1
        return True

    def release(self) -> None:
        self.lock.release()

    def let_waiting_go(self, stopped: Callable[[], bool]) -> None:
        """Before a step: wait while restyles wait for the lock (or until `stopped()`)."""
        while self._waiting and not stopped():
            time.sleep(0.002)

    def __enter__(self):
        self.lock.acquire()
        return self

    def __exit__(self, *exc):
        self.lock.release()


class Schedule:
    """The steps of the module doc, for one job.

    Args:
        plan: makes the render's `pipeline.runner.Runner` (called once, in the first pass's step,
            under the lock: loading and resolving trace Dr.Jit kernels).
        draft: makes the draft's runner (a `Job.draft` job), or None: no draft.
        clock: seconds, for the stats and `rules.denoise_now` (default `time.perf_counter`).
        turns: the lock (`Turns`; None: a new one).
        on_frame: called under the lock with each new `Frame`, or None.
        after_step: called under the lock after every step, shown or not (a restyle kept for the
            render thread), or None.
        warm: called under the lock once the final image is shown (the adapter's warm-up), or
            None.
        first: called under the lock as the first step, before the draft (the viewport's
            carried image, which the adapter shows itself: no Frame), or None.

    Takes more than 7 parameters: after the plan and the draft, each is an adapter's hook into one
    moment of the steps (the clock, the lock, a frame, every step, the end, the start), all
    keywords, each optional.

    `frames`: every Frame shown; `stats`: `draft_s`, `first_s`, `final_s` (seconds from the start
    to those images), `pass_s` (each pass's seconds), `denoise_s` (each denoising's); `spp_done`;
    `runner` (after the first pass's step); `done`; `error` (a step's failure, one line).
    """

    def __init__(self, plan: Callable[[], Runner], draft: Callable[[], Runner] | None = None, *,
                 clock: Callable[[], float] = time.perf_counter, turns: Turns | None = None,
                 on_frame: Callable[[Frame], None] | None = None,
                 after_step: Callable[[], None] | None = None,
                 warm: Callable[[], None] | None = None,
                 first: Callable[[], None] | None = None):
        self._plan, self._draft, self._first = plan, draft, first
        self.clock = clock
        self.turns = turns if turns is not None else Turns()
        self.on_frame, self.after_step, self.warm = on_frame, after_step, warm
        self.frames: list[Frame] = []
        self.stats: dict[str, Any] = {"draft_s": None, "first_s": None, "final_s": None,
                                      "pass_s": [], "denoise_s": []}
        self.runner: Runner | None = None
        self.spp_done = 0
        self.error: str | None = None
        self.started: float | None = None
        self._steps: Iterator[Frame | None] | None = None
        self._done = False
        self._stop = threading.Event()
        self._thread: threading.Thread | None = None

    # ---- driving ----------------------------------------------------------------------------

    @property
    def done(self) -> bool:
        """Whether every step has run (or one failed, or the schedule was stopped) and the thread,
        where started, has ended."""
        return self._done and (self._thread is None or not self._thread.is_alive())

    def step(self) -> Frame | None:
        """Run the next step (module doc) under the lock.

        Returns:
            The Frame it shows, or None (the image on screen stays; or every step has run).

        Raises:
            Exception: a step's failure (the schedule is then done; `run` keeps it in `error`).
        """
        if self._done:
            return None
        if self._steps is None:
            self.started = self.clock()
            self._steps = self._all_steps()
        try:
            return next(self._steps)
        except StopIteration:
            self._done = True
            return None
        except BaseException:
            self._done = True
            raise

    def run(self) -> None:
        """Every step, until done or stopped; a failure is kept in `error` (one line), the images
        shown stay."""
        try:
            while not self._done and not self._stop.is_set():
                self.turns.let_waiting_go(self._stop.is_set)
                self.step()
        except Exception as exc:  # shown by the view; the images done stay usable
            text = str(exc).strip().splitlines()
            self.error = text[0] if text else type(exc).__name__
        finally:
            self._done = True

    def start(self, name: str = "styletrace-progressive",
              then: Callable[[], None] | None = None) -> "Schedule":
        """Run the steps in a daemon thread.

        Args:
            name: the thread's name. then: called in that thread after the steps, unless stopped
                (the viewport collects its garbage there), or None.

        Returns:
            This schedule.
        """
        def work():
            self.run()
            if then is not None and not self._stop.is_set():
                then()

        self._thread = threading.Thread(target=work, name=name, daemon=True)
        self._thread.start()
        return self

    def stop(self, wait: float = 0.0) -> None:
        """Stop after the step under way.

        Args:
            wait: seconds to wait at most for the thread to end; 0 returns at once.
        """
        self._stop.set()
        if wait and self._thread is not None:
            self._thread.join(wait)

    @property
    def stopped(self) -> bool:
        return self._stop.is_set()

    def join(self, timeout: float | None = None) -> None:
        """Wait for the thread to end (None: until it does)."""
        if self._thread is not None:
            self._thread.join(timeout)

    # ---- the steps --------------------------------------------------------------------------

    def _since_start(self) -> float:
        return self.clock() - self.started

    def _show(self, kind: str, label: str, image: np.ndarray, buffer: Any, prog,
              children: int, denoiser=None) -> Frame:
        """Make a Frame of the passes up to `prog` the newest image (under the lock) and tell
        `on_frame`."""
        frame = Frame(kind, label, np.asarray(image[..., :3], dtype=np.float32), buffer,
                      int(prog.spp_done), int(children), len(self.frames) + 1,
                      self._since_start(), denoiser)
        self.frames.append(frame)
        if self.stats["first_s"] is None:
            self.stats["first_s"] = frame.seconds
        if kind == "final":
            self.stats["final_s"] = frame.seconds
        if self.on_frame is not None:
            self.on_frame(frame)
        return frame

    def _after(self) -> None:
        if self.after_step is not None:
            self.after_step()

    def _all_steps(self) -> Iterator[Frame | None]:
        """The steps, each computed under the lock (the generator yields outside it)."""
        if self._first is not None:
            with self.turns:
                self._first()
                self._after()
            yield None
            if self._stop.is_set():
                return
        if self._draft is not None:
            with self.turns:
                frame = self._draft_frame()
                self._after()
            yield frame
            if self._stop.is_set():
                return
        yield from self._pass_steps()
        if self.warm is not None and not self._stop.is_set():
            with self.turns:
                self.warm()
                self._after()

    def _draft_frame(self) -> Frame:
        runner = self._draft()
        prog = next(iter(runner.passes()))
        finisher = runner.finisher
        children = children_of(runner)
        w, h = runner.resolved.size
        label = f"draft, denoised ({w}x{h}, 1 spp)"
        if isinstance(finisher, Expectation):
            image, buf = finisher.job.preview(PREVIEW_K, PREVIEW_QUALITY)
            frame = self._show("draft", label, image, buf, prog, children)
        elif isinstance(finisher, Denoised):
            image = runner.finish(prog)
            frame = self._show("draft", label, image, getattr(finisher, "recorded", None), prog,
                               children, denoiser_of(finisher, prog))
        else:
            frame = self._show("draft", f"draft ({w}x{h}, 1 spp)", prog.image,
                               getattr(finisher, "recorded", None), prog, children)
        self.stats["draft_s"] = frame.seconds
        return frame

    def _pass_steps(self) -> Iterator[Frame | None]:
        with self.turns:
            self.runner = runner = self._plan()
            passes = runner.passes()
        finisher, total = runner.finisher, runner.resolved.launches
        denoised = isinstance(finisher, Denoised)
        children = children_of(runner)
        since = 0.0  # seconds of passes since the last denoised image
        state = _State()
        for k in range(1, total + 1):
            if self._stop.is_set():
                return
            final_next = False
            with self.turns:
                start = self.clock()
                prog = next(passes, None)
                if prog is None:
                    return
                seconds = self.clock() - start
                self.stats["pass_s"].append(seconds)
                self.spp_done = prog.spp_done
                since += seconds
                label = f"pass {k}/{total}, {prog.spp_done} spp"
                last = k == total
                if not denoised or not finisher.ready(prog):
                    frame = self._show("final" if last and not denoised else "pass", label,
                                       prog.image, getattr(finisher, "recorded", None), prog,
                                       children)
                elif last and state.previewing and self._quick_serves(finisher, prog):
                    # a render of one pass: a quick look first, the finisher in the next step
                    frame, final_next = self._quick(finisher, prog, label, children, state), True
                elif last:
                    frame = self._final(runner, prog, label, children)
                elif (denoise_now(k, total, since, self.stats["denoise_s"])
                      and worth_showing(prog.spp_done, state.shown_spp)):
                    frame = self._preview(runner, prog, label, children, state)
                    since = 0.0
                else:
                    frame = None  # the last denoised image stays on screen
                self._after()
            yield frame
            if final_next and not self._stop.is_set():
                with self.turns:
                    frame = self._final(runner, prog, label, children)
                    self._after()
                yield frame

    def _final(self, runner: Runner, prog, label: str, children: int) -> Frame:
        """The render's own finisher on every pass: the final image (under the lock)."""
        start = self.clock()
        image = runner.finish(prog)
        self.stats["denoise_s"].append(self.clock() - start)
        finisher = runner.finisher
        return self._show("final", label + ", denoised", image, final_buffer(finisher), prog,
                          children, denoiser_of(finisher, prog))

    @staticmethod
    def _quick_serves(finisher, prog) -> bool:
        return isinstance(finisher, Expectation) and quick_serves(prog.spp_done)

    def _quick(self, finisher: Expectation, prog, label: str, children: int, state) -> Frame:
        """A quick preview of the passes so far (`rules.PREVIEW_K`, `rules.PREVIEW_QUALITY`)."""
        start = self.clock()
        image, buf = finisher.job.preview(PREVIEW_K, PREVIEW_QUALITY)
        self.stats["denoise_s"].append(self.clock() - start)
        state.previewing, state.shown_spp = False, prog.spp_done
        return self._show("preview", label + ", denoised (preview)", image, buf, prog, children)

    def _preview(self, runner: Runner, prog, label: str, children: int, state) -> Frame:
        """A denoised image of the passes so far (module doc, step 2): quick where it serves, else
        the render's own denoiser (under the lock)."""
        finisher = runner.finisher
        if state.previewing and self._quick_serves(finisher, prog):
            return self._quick(finisher, prog, label, children, state)
        start = self.clock()
        if isinstance(finisher, Expectation):
            # the finisher's own coverage and quality, on the passes so far; `finish` untouched
            image, buf = finisher.job.preview(finisher.coverage, finisher.quality)
            denoiser = None
        else:
            image, buf = runner.finish(prog), getattr(finisher, "recorded", None)
            denoiser = denoiser_of(finisher, prog)
        self.stats["denoise_s"].append(self.clock() - start)
        state.previewing, state.shown_spp = False, prog.spp_done
        return self._show("preview", f"{label}, denoised", image, buf, prog, children, denoiser)


class _State:
    """What the pass steps remember: whether a full-size denoised image is yet to be shown
    (`previewing`: only the first may be a quick preview), and the camera samples per pixel of
    the one on screen (`shown_spp`)."""

    def __init__(self):
        self.previewing = True
        self.shown_spp = 0


def children_of(runner: Runner) -> int:
    """Children per camera sample at the first stylized level of a run (1 without children)."""
    return int(runner.resolved.budget.children[0]) if not runner.resolved.budget.request.closed \
        else 1


def final_buffer(finisher) -> Any:
    """The buffer that restyles to a finisher's final image: the denoised one it kept
    (`Expectation`'s `keep`), else the recorded one, else None."""
    kept = getattr(finisher, "kept", None)
    return kept if kept is not None else getattr(finisher, "recorded", None)


def denoiser_of(finisher, prog) -> Callable[[np.ndarray], np.ndarray] | None:
    """What turns a restyle of the finisher's recorded buffer into its denoised image: the image
    denoiser's OIDN with the guides of `prog`'s passes (`denoise.finishers.Image.denoiser`), or
    None (the expectation denoiser's buffer holds D; an undenoised restyle is the image)."""
    make = getattr(finisher, "denoiser", None)
    if make is None or getattr(finisher, "recorded", None) is None:
        return None
    return make(prog)


__all__ = ["Schedule", "Frame", "Turns", "children_of", "denoiser_of"]
