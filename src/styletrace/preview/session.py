"""One preview session: a scene, an expectation buffer rendered in the background, restyles of it.

    s = Session("cornell-box", samples=16).start()       # the background thread renders
    image, spp, n = s.restyle("cel", None, {})            # the newest image's buffer, restyled
    r = s.styled("cel", None, {"levels": "0.2,0.6"}, quick=True, wait=False)   # a drag's value

A background thread follows Blender's viewport's schedule (docs/design/viewport.md, "The
schedule"): first the **draft** (1 spp, one child per camera sample, denoised where it can:
`denoise.draft`), then the render the page's command line names (`command`), one camera sample
per pass (the samples split into spp x n by `pipeline.budget.split` for the style the page starts
with; recorded with the `identity` style, so every style restyles it). Where the render denoises
(`denoise.default`), the first pass and the passes `denoise.progressive.denoise_now` picks get a
quick denoised preview (`ExpectationJob.preview`), the last the render's own finisher, whose
buffer restyles to the command line's image; the passes between keep the last denoised image.
Undenoised, every pass is shown. Restyles use the newest image's buffer: the whole buffer
(`lookdev.restyle.restyle`) or, while a slider is dragged, one point per pixel
(`lookdev.slider.quick_restyle`). Dr.Jit work of every thread runs under one lock, `jit`; a
restyle that must not wait for it keeps its style for the render thread, which restyles it after
its pass. Design: docs/design/preview_session.md.
"""
from __future__ import annotations

import threading
import time
from dataclasses import dataclass, replace
from typing import Any, Callable

import numpy as np

from styletrace.denoise.default import check_method, default_method
from styletrace.denoise.draft import QUALITY as DRAFT_QUALITY
from styletrace.denoise.draft import available as denoise_available
from styletrace.denoise.draft import draft as denoise_draft
from styletrace.denoise.finishers import plan_finisher
from styletrace.denoise.progressive import PREVIEW_K, PREVIEW_QUALITY, denoise_now
from styletrace.errors import UsageError
from styletrace.lookdev.buffer import MAX_SAMPLES, Buffer, bytes_per_sample
from styletrace.lookdev.record import Recorded, scene_label
from styletrace.lookdev.restyle import restyle, slots_for
from styletrace.lookdev.slider import quick_restyle
from styletrace.pipeline.budget import Request, split
from styletrace.pipeline.execute import InProcess
from styletrace.pipeline.job import Job
from styletrace.pipeline.resolve import resolve
from styletrace.pipeline.runner import Runner
from styletrace.scene.loading import first_line, load_scene, scene_spp
from styletrace.styles.registry import style_class

#: OIDN's quality of the last image: the command line's default (`--denoise-quality`)
FULL_QUALITY = "high"
#: where g meets D in the last image: the command line's default (`--coverage`)
FULL_COVERAGE = "auto"

DEFAULT_SIZE = 256
#: the style the page starts with where the caller names none (its default n sets the split)
DEFAULT_STYLE = "cel"
DRAFT_INNER = 1  # children per camera sample of the draft pass
#: how long the render thread waits, after the draft, for a restyle to show it before the first
#: full pass takes the lock for about a second (the page polls every 0.3 s; measured: the first
#: request can arrive 0.2 s after the draft is done)
DRAFT_GRACE_S = 1.0
#: the kinds of image, in the order the schedule shows them
KINDS = ("draft", "pass", "preview", "final")


@dataclass(frozen=True)
class Shown:
    """An image of the schedule: what the page's restyles read.

    Args:
        kind: "draft", "pass" (undenoised), "preview" (`ExpectationJob.preview`) or "final" (the
            command line's image; undenoised, the last pass).
        label: how the page names it, e.g. "pass 1/4, 1 spp, denoised (preview)".
        spp: camera samples per pixel in it. inner: children per camera sample.
        version: its number, from 1, in the order shown. seconds: from the session's start.
    """
    kind: str
    label: str
    spp: int
    inner: int
    version: int
    seconds: float


@dataclass(frozen=True)
class Styled:
    """A restyle's answer (`Session.styled`).

    Args:
        image: H x W x 3 float32, linear; None before the draft, or while busy with nothing kept.
        shown: the image of the schedule it restyles (None before the draft).
        quick: whether it is one point per pixel (`lookdev.slider.quick_restyle`).
        busy: the lock was held by a pass or a denoising: the style is kept for the render
            thread, and `image` is the newest one it restyled for a request of the same style and
            estimator (or None).
        stamp: the restyle's number, from 1, in the order they were made (a page shows an
            answer only if it is newer than the one on screen). seconds: the restyle's own time.
        key: what it restyled (style, estimator, params, quick).
    """
    image: np.ndarray | None
    shown: Shown | None
    quick: bool = False
    busy: bool = False
    stamp: int = 0
    seconds: float = 0.0
    key: tuple = ()


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
    """A preview of `scene`: the draft and the command line's render in a background thread,
    their images restyled on request (module doc).

    Args:
        scene, width, height, seed: the render's (a built-in scene defaults to DEFAULT_SIZE square).
        samples: paths per pixel (None: the scene's sample count), split into spp x inner by
            `pipeline.budget.split` for `style`'s default n, within the cap.
        inner, spp: children per camera sample and camera samples per pixel (None: from samples).
        style: the style the page starts with (its default n splits the samples).
        max_samples: the buffer's cap. denoise: auto, expectation or off (`denoise.default`; None:
            the default).
        on_image: called in the render thread, under `jit`, with (the image's buffer, its
            `Shown`) after each new image; None: nothing is called.

    Raises:
        UsageError: over the cap, denoise 'image', samples that disagree with spp and inner, or a
            refusal of a run (one line each).

    `stats`: `draft_s`, `final_s` (seconds from the start to those images), `pass_s` (each pass's
    seconds) and `denoise_s` (each denoising's); `shown`: every `Shown` so far; `counts`: the
    restyles made (`quick`, `full`), answered from the kept one (`kept`) and found busy (`busy`).
    """

    def __init__(self, scene: Any = None, inner: int | None = None, spp: int | None = None,
                 width: int | None = None, height: int | None = None, seed: int = 0,
                 max_samples: int = MAX_SAMPLES, denoise: str | None = None,
                 samples: int | None = None, style: str = DEFAULT_STYLE,
                 on_image: Callable[[Buffer, Shown], None] | None = None):
        self.label = scene_label(scene)
        builtin = isinstance(scene, str) and not scene.lower().endswith(".xml") or scene is None
        w = width or (DEFAULT_SIZE if builtin else None)
        h = height or (DEFAULT_SIZE if builtin else None)
        self.size = (w, h)
        self.seed = seed
        self.max_samples = max_samples
        self.scene = load_scene(scene, w, h)
        film = self.scene.sensors()[0].film().crop_size()
        self.width, self.height = int(film[0]), int(film[1])
        # the render's rule, for the style the page starts with: its n is what restyles see; an
        # auto spp stays within the buffer's cap
        request = Request(scene_spp(self.scene) if samples is None else int(samples), spp,
                          None if inner is None else (int(inner),),
                          style_class(style).default_inner, samples_given=samples is not None,
                          denoised=check_method(denoise or default_method()) != "off")
        self.budget = split(request, max(1, max_samples // (self.width * self.height)))
        self.inner, self.spp = int(self.budget.inner[0]), self.budget.spp
        if self.width * self.height * self.spp > max_samples:
            raise UsageError(f"{self.width}x{self.height} at {self.spp} spp is "
                             f"{self.width * self.height * self.spp} camera samples, over the "
                             f"preview's cap of {max_samples}; lower --spp or the size")
        if denoise == "image":
            raise UsageError("the preview restyles the expectation: denoise 'image' would hide "
                             "what the styles see; use expectation, auto or off")
        # the command line's render (`command`): one camera sample per pass (--pass-spp 1), the
        # scene's own max_depth, rr_depth and hide_emitters kept, recorded with `identity`
        self.job = Job(scene=scene, width=w, height=h, spp=self.spp, seed=seed, pass_spp=1,
                       given={"style": "identity", "inner_samples": self.inner})
        resolved = resolve(self.job, self.scene)
        self.integrator = resolved.integrator
        # every front end's default (`denoise.default`): the expectation denoised where it applies
        from styletrace.denoise.default import method_for
        method, self.note = method_for(self.scene, self.integrator, denoise)
        self.denoised = method == "expectation" and denoise_available()
        # the command line's finisher (`plan_finisher`: with the firefly control where it
        # denoises), so that the last image is the command line's
        self.runner = plan_finisher(resolved, "expectation" if self.denoised else "off",
                                    quality=FULL_QUALITY, coverage=FULL_COVERAGE,
                                    label=self.label, keep=self._keep)[0]
        draft_job = self.job.with_(given={**self.job.given, "inner_samples": DRAFT_INNER}, spp=1)
        self.draft_runner = Runner(resolve(draft_job, self.scene), InProcess(),
                                   Recorded(label=self.label, max_samples=max_samples))
        self.on_image = on_image
        self.jit = threading.Lock()
        self._waiting = 0  # restyles waiting for `jit`: the render thread lets them first
        self._count = threading.Lock()  # `_waiting`, `_wanted`, `_kept`, `counts`
        self._draft_shown = threading.Event()
        self.buffer: Buffer | None = None  # the newest full-size image's buffer (after the draft)
        self.draft: Buffer | None = None  # 1 spp, n = DRAFT_INNER; shown until the first pass
        self.draft_denoised = False  # the draft holds a denoised expectation (the `denoise` extra)
        self.current: Shown | None = None
        self.shown: list[Shown] = []
        self.spp_done = 0
        self.finished = False  # the last image is in
        self.error: str | None = None
        self.initial: dict[str, Any] = {"style": style, "params": {}}   # what the page starts with
        self.started = time.perf_counter()
        self.first_image_s: float | None = None
        self.stats: dict[str, Any] = {"pass_s": [], "denoise_s": []}
        self.counts = {"quick": 0, "full": 0, "kept": 0, "busy": 0}
        #: the newest request that found `jit` busy: the render thread restyles it after its pass
        self._wanted: tuple | None = None
        #: the newest restyle made (`Styled`): answers a request for the same key and image
        self._kept: Styled | None = None
        #: the newest restyle the render thread made (of a busy request's style, or of the newest
        #: request's on a new image): a busy request for the same style is answered with it
        self._by_render: Styled | None = None
        self._stamp = 0
        self._final: Buffer | None = None
        self._previewing = True  # no full-size denoised image shown yet: a preview comes first
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._render, name="styletrace-preview-render",
                                        daemon=True)

    def start(self) -> "Session":
        """Start the render thread. Returns: this session."""
        self._thread.start()
        return self

    def stop(self) -> None:
        """Stop the render thread after its pass under way (waits up to 60 s for it)."""
        self._stop.set()
        self._draft_shown.set()
        self._thread.join(timeout=60)

    def join(self, timeout: float | None = None) -> None:
        """Wait for the render thread to end.

        Args:
            timeout: seconds to wait at most; None waits until it ends.
        """
        self._thread.join(timeout)

    def _keep(self, buf: Buffer) -> None:
        self._final = buf  # the finisher's buffer (`Expectation`): restyles to its image

    # ---- the render thread ---------------------------------------------------------------------

    def _render(self) -> None:
        """The draft, then the command line's passes, each under `jit` (module doc)."""
        try:
            if self.inner > DRAFT_INNER and not self._stop.is_set():
                self._run_draft()
                self._draft_shown.wait(DRAFT_GRACE_S)
            self._run_passes()
            self._warm_quick_restyle()
        except Exception as exc:  # shown on the page; the images done stay usable
            self.error = first_line(exc)

    def _run_draft(self) -> None:
        draft = self.draft_runner.passes()
        with self.jit:
            next(draft)
            buf = self.draft_runner.finisher.recorded
            self.draft_denoised = denoise_draft(buf, self.scene, self.seed)  # docs/denoise.md
            self.draft = buf
            how = ", denoised" if self.draft_denoised else ""
            self._show(buf, "draft", f"draft{how} (1 spp, {DRAFT_INNER} child per sample)", 1,
                       DRAFT_INNER)
        self.stats["draft_s"] = self.current.seconds

    def _run_passes(self) -> None:
        """One camera sample per pass; the images the schedule shows (module doc)."""
        passes = self.runner.passes()
        total = self.spp  # --pass-spp 1
        since = 0.0  # seconds of passes since the last denoised image
        for k in range(1, total + 1):
            if self._stop.is_set():
                return
            self._yield_to_restyles()
            with self.jit:
                start = time.perf_counter()
                prog = next(passes, None)
                if prog is None:
                    return
                seconds = time.perf_counter() - start
                self.stats["pass_s"].append(seconds)
                self.spp_done = prog.spp_done
                since += seconds
                label = f"pass {k}/{total}, {prog.spp_done} spp"
                last = k == total
                if not self.denoised:
                    self._show(self.runner.finisher.recorded, "final" if last else "pass", label,
                               prog.spp_done, self.inner)
                    continue
                # a request found the lock busy during the pass: its style now, on the image
                # shown, before a denoising holds the lock longer
                self._restyle_wanted()
                if denoise_now(k, total, since, self.stats["denoise_s"]):
                    self._denoised(prog, label, last)
                    since = 0.0
        self.finished = True
        self.stats["final_s"] = time.perf_counter() - self.started

    def _denoised(self, prog, label: str, last: bool) -> None:
        """The denoised images of a pass, under `jit`: a preview unless this is the last pass and
        a full-size denoised image is on screen already; after the last pass the render's own
        finisher (what the command line writes)."""
        if not last or self._previewing:
            start = time.perf_counter()
            _, buf = self.runner.finisher.job.preview(PREVIEW_K, PREVIEW_QUALITY)
            self.stats["denoise_s"].append(time.perf_counter() - start)
            self._previewing = False
            self._show(buf, "preview", label + ", denoised (preview)", prog.spp_done, self.inner)
        if last:
            start = time.perf_counter()
            self.runner.finish(prog)  # `_keep` gets its buffer
            self.stats["denoise_s"].append(time.perf_counter() - start)
            self._show(self._final, "final", label + ", denoised", prog.spp_done, self.inner)

    def _show(self, buf: Buffer, kind: str, label: str, spp: int, inner: int) -> None:
        """Make `buf` the image restyles read (under `jit`); restyle the style a busy request
        kept; tell `on_image`."""
        shown = Shown(kind, label, int(spp), int(inner), len(self.shown) + 1,
                      time.perf_counter() - self.started)
        if kind != "draft":
            self.buffer = buf
        self.current = shown
        self.shown.append(shown)
        # the page's newest style, restyled now: its next request for it is answered at once
        with self._count:
            if self._wanted is None and self._kept is not None:
                self._wanted = self._kept.key
        self._restyle_wanted()
        if self.on_image is not None:
            self.on_image(buf, shown)

    def _restyle_wanted(self) -> None:
        """Restyle the newest style a request named (under `jit`), to answer it without the
        lock; a style the buffer refuses is dropped (its request got its one line)."""
        with self._count:
            key, self._wanted = self._wanted, None
        if key is None:
            return
        style, estimator, params, quick = key
        try:
            styled = self._restyled(style, estimator, dict(params), quick)
        except Exception:  # noqa: BLE001 - the request that named it was answered already
            return
        with self._count:
            self._by_render = styled

    def _warm_quick_restyle(self) -> None:
        """Trace and compile the quick restyle of the last buffer (`lookdev.slider`) before the
        first drag needs it: the one-point-per-pixel view and its kernel, for the page's style."""
        if self.buffer is None or self._stop.is_set():
            return
        kept = self._kept
        style, estimator, params = (
            (kept.key[0], kept.key[1], dict(kept.key[2])) if kept is not None else
            (self.initial["style"], None, dict(self.initial["params"])))
        with self.jit:
            try:
                quick_restyle(self.buffer, style=style, estimator=estimator, **params)
            except Exception:  # noqa: BLE001 - a style the view refuses: drags restyle in full
                pass
            self._restyle_wanted()  # a request that came meanwhile

    def _yield_to_restyles(self) -> None:
        """Wait while restyles are queued for the lock: a pass takes about a second, a restyle a few
        ms, and Python's lock is not fair (the render thread would take it again at once and starve
        the page)."""
        while self._waiting and not self._stop.is_set():
            time.sleep(0.002)

    # ---- restyles --------------------------------------------------------------------------------

    @property
    def done(self) -> bool:
        """Whether the last image is in."""
        return self.finished

    def _readable(self) -> Buffer | None:
        return self.buffer if self.buffer is not None else self.draft

    def restyle(self, style: str, estimator: str | None, params: dict[str, Any],
                quick: bool = False) -> tuple[np.ndarray | None, int, int]:
        """The newest image's buffer restyled, waiting for a pass that holds the lock.

        Args:
            style: the style's name. params: its parameters, {name: value}.
            estimator: the estimator's name (None: the recorded one where it applies).
            quick: one point per pixel (`lookdev.slider.quick_restyle`), else the whole buffer.

        Returns:
            (the image, H x W x 3, or None before the draft finished; its spp; its n children).

        Raises:
            StyletraceError: a refused style, estimator or value (one line).
        """
        r = self.styled(style, estimator, params, quick=quick)
        shown = r.shown or Shown("draft", "", 0, 0, 0, 0.0)
        return r.image, shown.spp, shown.inner

    def styled(self, style: str, estimator: str | None, params: dict[str, Any],
               quick: bool = False, wait: bool = True) -> Styled:
        """The newest image's buffer restyled: the whole buffer (`lookdev.restyle.restyle`) or one
        point per pixel with θ as kernel inputs (`quick`: a slider being dragged).

        Args:
            style, estimator, params: as `restyle`'s. quick: one point per pixel.
            wait: wait for a pass or a denoising that holds the lock (the render thread lets
                waiting restyles go first); False: answer at once, busy, and keep the style for
                the render thread, which restyles it after its pass (the page's next request for
                it is then answered without the lock).

        Returns:
            The `Styled`: the image None before the draft, and where busy with nothing restyled
            for this style yet. A request equal to the newest restyle's, on the same image, gets
            that restyle again (`counts["kept"]`).

        Raises:
            StyletraceError: a refused style, estimator or value (one line; checked on the host,
                busy or not).
        """
        key = request_key(style, estimator, params, quick)
        buf = self._readable()
        if buf is None:
            return Styled(None, None, quick, key=key)
        slots_for(buf, style=style, estimator=estimator, **params)  # a bad value: one line now
        kept = self._answer_kept(key)
        if kept is not None:
            return kept
        if wait:
            with self._count:
                self._waiting += 1
            try:
                self.jit.acquire()
            finally:
                with self._count:
                    self._waiting -= 1
        elif not self.jit.acquire(blocking=False):
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
            self.jit.release()

    def _answer_kept(self, key: tuple) -> Styled | None:
        """The newest restyle where it answers `key` on the newest image (a full restyle answers
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
        """A restyle of the newest image's buffer, under `jit`; kept to answer its key again."""
        buf, shown = self._readable(), self.current
        start = time.perf_counter()
        how = quick_restyle if quick else restyle
        img = how(buf, style=style, estimator=estimator, **params)
        seconds = time.perf_counter() - start
        if buf is self.draft and self.buffer is None:
            self._draft_shown.set()
        if self.first_image_s is None:
            self.first_image_s = time.perf_counter() - self.started
        with self._count:
            self._stamp += 1
            self.counts["quick" if quick else "full"] += 1
            out = Styled(img, shown, quick, False, self._stamp, seconds,
                         request_key(style, estimator, params, quick))
            self._kept = out
        return out

    def state(self) -> dict[str, Any]:
        """The page's view of the session (docs/preview.md, `GET /api/state`)."""
        filtered = self.buffer is not None and self.buffer.filtered
        per = bytes_per_sample("first_hit", filtered=filtered)
        cur = self.current
        with self._count:
            counts = dict(self.counts)
            busy_stamp = self._by_render.stamp if self._by_render is not None else 0
        return {"scene": self.label, "width": self.width, "height": self.height,
                "spp_done": self.spp_done, "spp": self.spp, "inner": self.inner,
                "samples": self.width * self.height * self.spp_done,
                "cap_samples": self.max_samples, "bytes_per_sample": per,
                "bytes": self.width * self.height * self.spp_done * per, "error": self.error,
                "draft": self.buffer is None and self.draft is not None,
                "draft_denoised": self.buffer is None and self.draft_denoised,
                "denoised": self.denoised, "note": self.note,
                "version": cur.version if cur else 0, "kind": cur.kind if cur else None,
                "label": cur.label if cur else "", "done": self.finished,
                "restyled": busy_stamp, "counts": counts,
                "images": [{"kind": s.kind, "label": s.label, "spp": s.spp,
                            "s": round(s.seconds, 3)} for s in self.shown],
                "initial": self.initial}

    def command(self, style: str, estimator: str | None, params: dict[str, Any],
                spp: int | None = None, inner: int | None = None) -> str:
        """The `styletrace render` command line of the render the session ends with (its last
        image, restyled as the page shows it), or of the draft.

        Args:
            style, estimator, params: what the page shows.
            spp, inner: those of the draft (1 and DRAFT_INNER) for the draft's command, or None:
                the session's render.

        Returns:
            The command line, quoted for a shell.
        """
        import shlex
        draft = (spp, inner) == (1, DRAFT_INNER) and inner != self.inner
        words = ["styletrace", "render", self.label, "--style", style,
                 "--inner", str(inner or self.inner), "--spp", str(spp or self.spp),
                 "--seed", str(self.seed), "--pass-spp", "1"]
        if estimator:
            words += ["--estimator", estimator]
        if draft and self.draft_denoised:  # the denoised draft's image: D at its camera samples
            words += ["--denoise", "expectation", "--coverage", "0",
                      "--denoise-quality", DRAFT_QUALITY]
        elif self.denoised and not draft:  # the finisher's: FULL_QUALITY, FULL_COVERAGE
            words += ["--denoise", "expectation"]
        else:
            words += ["--denoise", "off"]
        if self.size[0]:
            words += ["--width", str(self.width), "--height", str(self.height)]
        for k, v in params.items():
            words += ["--set", f"{k}={v}"]
        return shlex.join(words + ["-o", "render.png"])


__all__ = ["Session", "Shown", "Styled", "request_key", "KINDS"]
