"""One preview session: the page's render run by the one progressive schedule, restyled on request.

    s = Session(page_job("cornell-box", samples=16)).start()   # the schedule runs in a thread
    image, spp, n = s.restyle("cel", None, {})                 # the newest frame's buffer, restyled
    r = s.styled("cel", None, {"levels": "0.2,0.6"}, quick=True, wait=False)   # a drag's value

A session is a thin adapter around `progressive.schedule.Schedule`, the schedule Blender's
viewport runs: the draft, the passes (one camera sample each), the previews and the final image of
the render the page's command line names (`preview.jobs`: recorded with `identity`, so every style
restyles it), then the warm-up of the quick restyle. Restyles read the newest frame's buffer: the
whole buffer (`lookdev.restyle.restyle`), denoised as the render denoises (a frame's `denoiser`:
the image denoiser's OIDN where it finishes the render), or, while a slider is dragged, one point
per pixel (`lookdev.slider.quick_restyle`). A restyle that must not wait for the schedule's lock
keeps its style for the render thread, which restyles it after its step. Design:
docs/design/preview_session.md.
"""
from __future__ import annotations

import threading
import time
from dataclasses import dataclass, replace
from typing import Any, Callable

import numpy as np

from styletrace.denoise.finishers import Recording, plan
from styletrace.lookdev.buffer import Buffer, bytes_per_camera_sample
from styletrace.lookdev.restyle import restyle, slots_for
from styletrace.lookdev.slider import quick_restyle, quick_restyle_pixels
from styletrace.pipeline.job import Job
from styletrace.preview import jobs
from styletrace.progressive.schedule import Frame, Schedule


@dataclass(frozen=True)
class Styled:
    """A restyle's answer (`Session.styled`).

    Args:
        image: H x W x 3 float32, linear; None before the draft, or while busy with nothing kept.
        shown: the frame of the schedule it restyles (None before the draft).
        quick: whether it is one point per pixel (`lookdev.slider.quick_restyle`).
        busy: the lock was held by a step: the style is kept for the render thread, and `image`
            is the newest one it restyled for a request of the same style and estimator (or None).
        stamp: the restyle's number, from 1, in the order they were made (a page shows an
            answer only if it is newer than the one on screen). seconds: the restyle's own time.
        key: what it restyled (style, estimator, params, quick).
        pixels: a quick restyle's image as a page draws it, H x W x 4 uint8 sRGB RGBA, encoded
            on the device in the same trip (`lookdev.slider.quick_restyle_pixels`); else None.
    """
    image: np.ndarray | None
    shown: Frame | None
    quick: bool = False
    busy: bool = False
    stamp: int = 0
    seconds: float = 0.0
    key: tuple = ()
    pixels: np.ndarray | None = None


def request_key(style: str, estimator: str | None, params: dict[str, Any], quick: bool) -> tuple:
    """A restyle request as a hashable key (values as the page spells them).

    Args:
        style, estimator, params: the request's. quick: one point per pixel.

    Returns:
        (style, estimator, ((name, str(value)), ... sorted), quick).
    """
    return (style, estimator or None, tuple(sorted((str(k), str(v)) for k, v in params.items())),
            bool(quick))


class Session:
    """A preview of the page's job (`preview.jobs.page_job`): its schedule in a background thread,
    its frames restyled on request (module doc).

    Args:
        job: the page's render. on_image: called in the render thread, under the schedule's lock,
            with each new `Frame`; None: nothing is called.
        clock: the schedule's clock (default `time.perf_counter`).

    `initial`: what the page starts with ({"style", "params"}); `counts`: the restyles made
    (`quick`, `full`), answered from the kept one (`kept`) and found busy (`busy`).
    """

    def __init__(self, job: Job, on_image: Callable[[Frame], None] | None = None,
                 clock: Callable[[], float] = time.perf_counter):
        self.job = job
        style = dict(job.given)
        self.initial: dict[str, Any] = {"style": style.pop("style", jobs.DEFAULT_STYLE),
                                        "params": {k: v for k, v in style.items()
                                                   if k != "inner_samples"}}
        self.on_image = on_image
        self.prepared: jobs.Prepared | None = None
        self.draft_runner = None
        self.schedule = Schedule(self._plan, self._draft_plan, clock=clock,
                                 on_frame=self._on_frame, after_step=self._restyle_wanted,
                                 warm=self._warm)
        self.buffer: Buffer | None = None  # the newest full-size frame's buffer
        self.draft: Frame | None = None
        self.current: Frame | None = None
        self._count = threading.Lock()  # `_wanted`, `_kept`, `_by_render`, `counts`
        self.counts = {"quick": 0, "full": 0, "kept": 0, "busy": 0}
        #: the newest request that found the lock busy: the render thread restyles it after its step
        self._wanted: tuple | None = None
        #: the newest restyle made (`Styled`): answers a request for the same key and frame
        self._kept: Styled | None = None
        #: the newest restyle the render thread made: a busy request for its style gets it
        self._by_render: Styled | None = None
        self._stamp = 0

    # ---- the schedule -------------------------------------------------------------------------

    def start(self) -> "Session":
        """Prepare the jobs (`preview.jobs.prepare`: refusals are raised here, in one line), then
        run the schedule in a thread. Returns: this session."""
        self.prepared = jobs.prepare(self.job)
        self.schedule.start("styletrace-preview")
        return self

    def stop(self) -> None:
        """Stop the render thread after its step under way (waits up to 60 s for it)."""
        self.schedule.stop(60)

    def join(self, timeout: float | None = None) -> None:
        """Wait for the render thread to end (None: until it does)."""
        self.schedule.join(timeout)

    @property
    def done(self) -> bool:
        """Whether the final image is in and the warm-up done (or the schedule stopped)."""
        return self.schedule.done

    @property
    def error(self) -> str | None:
        return self.schedule.error

    @property
    def stats(self) -> dict:
        """The schedule's: `draft_s`, `first_s`, `final_s`, `pass_s`, `denoise_s`."""
        return self.schedule.stats

    @property
    def frames(self) -> list[Frame]:
        """Every frame shown so far."""
        return self.schedule.frames

    def _recording(self) -> Recording:
        return Recording(label=self.prepared.label, restyled=True)

    def _draft_plan(self):
        p = self.prepared
        self.draft_runner = plan(p.draft, scene=p.draft_scene, recording=self._recording())
        return self.draft_runner

    def _plan(self):
        p = self.prepared
        return plan(p.recording, scene=p.scene, recording=self._recording())

    def _on_frame(self, frame: Frame) -> None:
        """A new frame (under the lock): the one restyles read; the page's newest style restyled
        now, so that its next request is answered at once; `on_image` told."""
        if frame.kind == "draft":
            self.draft = frame
        else:
            self.buffer = frame.buffer
        self.current = frame
        with self._count:
            if self._wanted is None and self._kept is not None:
                self._wanted = self._kept.key
        self._restyle_wanted()
        if self.on_image is not None:
            self.on_image(frame)

    def _restyle_wanted(self) -> None:
        """Restyle the newest style a request named (under the lock), to answer it without the
        lock; a style the buffer refuses is dropped (its request got its one line)."""
        with self._count:
            key, self._wanted = self._wanted, None
        if key is None or self.current is None:
            return
        style, estimator, params, quick = key
        try:
            styled = self._restyled(style, estimator, dict(params), quick)
        except Exception:  # noqa: BLE001 - the request that named it was answered already
            return
        with self._count:
            self._by_render = styled

    def _warm(self) -> None:
        """Trace and compile the quick restyle of the last buffer (`lookdev.slider`) before the
        first drag needs it, for the page's style (under the lock)."""
        if self.buffer is None:
            return
        kept = self._kept
        style, estimator, params = (
            (kept.key[0], kept.key[1], dict(kept.key[2])) if kept is not None else
            (self.initial["style"], None, dict(self.initial["params"])))
        try:
            quick_restyle(self.buffer, style=style, estimator=estimator, **params)
        except Exception:  # noqa: BLE001 - a style the view refuses: drags restyle in full
            pass

    # ---- restyles -------------------------------------------------------------------------------

    def restyle(self, style: str, estimator: str | None, params: dict[str, Any],
                quick: bool = False) -> tuple[np.ndarray | None, int, int]:
        """The newest frame's buffer restyled, waiting for a step that holds the lock.

        Args:
            style: the style's name. params: its parameters, {name: value}.
            estimator: the estimator's name (None: the recorded one where it applies).
            quick: one point per pixel (`lookdev.slider.quick_restyle`), else the whole buffer.

        Returns:
            (the image, H x W x 3, or None before the draft; its camera samples per pixel; its
            children per camera sample).

        Raises:
            StyletraceError: a refused style, estimator or value (one line).
        """
        r = self.styled(style, estimator, params, quick=quick)
        return r.image, (r.shown.spp if r.shown else 0), (r.shown.children if r.shown else 0)

    def styled(self, style: str, estimator: str | None, params: dict[str, Any],
               quick: bool = False, wait: bool = True) -> Styled:
        """The newest frame's buffer restyled: the whole buffer, denoised as the render is
        (`Frame.denoiser`), or one point per pixel with θ as kernel inputs (`quick`: a slider being
        dragged).

        Args:
            style, estimator, params: as `restyle`'s. quick: one point per pixel.
            wait: wait for a step that holds the lock (waiting restyles go first); False: answer at
                once, busy, and keep the style for the render thread, which restyles it after its
                step (the page's next request for it is then answered without the lock).

        Returns:
            The `Styled`: the image None before the draft, and where busy with nothing restyled
            for this style yet. A request equal to the newest restyle's, on the same frame, gets
            that restyle again (`counts["kept"]`).

        Raises:
            StyletraceError: a refused style, estimator or value (one line; checked on the host,
                busy or not).
        """
        key = request_key(style, estimator, params, quick)
        frame = self.current
        if frame is None or frame.buffer is None:
            return Styled(None, frame, quick, key=key)
        slots_for(frame.buffer, style=style, estimator=estimator, **params)  # a bad value now
        kept = self._answer_kept(key)
        if kept is not None:
            return kept
        turns = self.schedule.turns
        if not turns.acquire(wait):
            with self._count:
                self._wanted = key
                self.counts["busy"] += 1
                last = self._by_render
            if last is None or last.key[:2] != key[:2]:  # another style or estimator
                return Styled(None, self.current, quick, busy=True, key=key)
            return replace(last, busy=True)
        try:
            return self._restyled(style, estimator, params, quick)
        finally:
            turns.release()

    def _answer_kept(self, key: tuple) -> Styled | None:
        """The newest restyle where it answers `key` on the newest frame (a full restyle answers
        a quick request too)."""
        with self._count:
            k = self._kept
            if k is None or k.shown is not self.current:
                return None
            if k.key != key and k.key != key[:3] + (False,):
                return None
            self.counts["kept"] += 1
            return k

    def _restyled(self, style: str, estimator: str | None, params: dict[str, Any],
                  quick: bool) -> Styled:
        """A restyle of the newest frame's buffer, under the lock; kept to answer its key again."""
        frame = self.current
        start = time.perf_counter()
        pixels = None
        if quick:
            img, pixels = quick_restyle_pixels(frame.buffer, style=style, estimator=estimator,
                                               **params)
        else:
            img = restyle(frame.buffer, style=style, estimator=estimator, **params)
            if frame.denoiser is not None:  # the image denoiser finishes the render
                img = frame.denoiser(img)
        seconds = time.perf_counter() - start
        with self._count:
            self._stamp += 1
            self.counts["quick" if quick else "full"] += 1
            out = Styled(img, frame, quick, False, self._stamp, seconds,
                         request_key(style, estimator, params, quick), pixels)
            self._kept = out
        return out

    # ---- what the page reads ----------------------------------------------------------------

    def state(self) -> dict[str, Any]:
        """The page's view of the session (docs/preview.md, `GET /api/state`)."""
        p, cur, s = self.prepared, self.current, self.schedule
        page = p.page if p is not None else None
        width, height = page.size if page is not None else (0, 0)
        filtered = self.buffer is not None and self.buffer.filtered
        per = bytes_per_camera_sample("first_hit", filtered=filtered)
        recorded = width * height * s.spp_done
        with self._count:
            counts = dict(self.counts)
            busy_stamp = self._by_render.stamp if self._by_render is not None else 0
        return {"scene": p.label if p else "", "width": width, "height": height,
                "samples": page.budget.paths if page else 0,
                "spp": page.spp if page else 0,
                "children": int(page.budget.children[0]) if page else 0,
                "spp_done": s.spp_done, "camera_samples": recorded,
                "cap_camera_samples": self.job.cap, "bytes_per_camera_sample": per,
                "bytes": recorded * per, "error": s.error,
                "draft": cur is not None and cur.kind == "draft",
                "method": page.method if page else None, "note": page.note if page else "",
                "version": cur.version if cur else 0, "kind": cur.kind if cur else None,
                "label": cur.label if cur else "", "done": s.done,
                "restyled": busy_stamp, "counts": counts,
                "images": [{"kind": f.kind, "label": f.label, "spp": f.spp,
                            "s": round(f.seconds, 3)} for f in s.frames],
                "initial": self.initial}

    def command(self, style: str, estimator: str | None, params: dict[str, Any],
                draft: bool = False) -> str:
        """The `styletrace render` command line of the render the session ends with (its final
        image restyled as the page shows it), or of the draft (`preview.jobs.command`).

        Args:
            style, estimator, params: what the page shows. draft: the draft's command line.

        Returns:
            The command line, quoted for a shell.
        """
        return jobs.command(self.prepared, style, estimator, params,
                            self.draft_runner if draft else None)


__all__ = ["Session", "Styled", "request_key"]
