"""One preview session: a scene, a growing expectation buffer rendered in the background, restyles
of it.

    s = Session("cornell-box", samples=64).start()   # the background thread records
    image, spp, n = s.restyle("cel", None, {})        # the buffer so far, restyled

A background thread takes the passes of two pipeline runs (`pipeline.runner.Runner`, in process,
one pass = the whole film at 1 spp): first the **draft** (1 spp, one child per camera sample,
denoised where it can: `denoise.draft`), shown until the first full pass is done; then the full
passes (the `identity` style, n children; recorded, with D attached where the default denoises).
The samples (paths per pixel; default the scene's) are split into spp x n by the render's rule
(`pipeline.budget.split`) for the style the page starts with; a given spp or inner wins.
Dr.Jit work of both threads runs under one lock, `jit`. Design: docs/design/preview_session.md.
"""
from __future__ import annotations

import threading
import time
from typing import Any

import numpy as np

from styletrace.denoise.draft import QUALITY as DRAFT_QUALITY
from styletrace.denoise.draft import available as denoise_available
from styletrace.denoise.draft import draft as denoise_draft
from styletrace.denoise.finishers import Expectation
from styletrace.errors import UsageError
from styletrace.lookdev.buffer import MAX_SAMPLES, Buffer, bytes_per_sample
from styletrace.lookdev.record import Recorded, scene_label
from styletrace.lookdev.restyle import restyle
from styletrace.pipeline.budget import Request, split
from styletrace.pipeline.execute import InProcess
from styletrace.pipeline.job import Job
from styletrace.pipeline.resolve import resolve
from styletrace.pipeline.runner import Runner
from styletrace.scene.loading import first_line, load_scene, scene_spp
from styletrace.styles.registry import style_class

#: OIDN's quality on the full passes (the draft's is `denoise.draft.QUALITY`)
FULL_QUALITY = "high"

DEFAULT_SIZE = 256
#: the style the page starts with where the caller names none (its default n sets the split)
DEFAULT_STYLE = "cel"
DRAFT_INNER = 1  # children per camera sample of the draft pass
#: how long the render thread waits, after the draft, for a restyle to show it before the first
#: full pass takes the lock for about a second (the page polls every 0.3 s; measured: the first
#: request can arrive 0.2 s after the draft is done)
DRAFT_GRACE_S = 1.0


class Session:
    """A preview of `scene`: its passes recorded in a background thread through two runs
    (`pipeline.runner.Runner`, in process), the draft's and the full passes', restyled on request.

    Args:
        scene, width, height, seed: the render's (a built-in scene defaults to DEFAULT_SIZE square).
        samples: paths per pixel of the full passes (None: the scene's sample count), split into
            spp x inner by `pipeline.budget.split` for `style`'s default n, within the cap.
        inner, spp: children per camera sample and camera samples per pixel of the full passes
            (None: from samples).
        style: the style the page starts with (its default n splits the samples).
        max_samples: the buffer's cap. denoise: auto, expectation or off (`denoise.default`).

    Raises:
        UsageError: over the cap, denoise 'image', samples that disagree with spp and inner, or a
            refusal of a run (one line each)."""

    def __init__(self, scene: Any = None, inner: int | None = None, spp: int | None = None,
                 width: int | None = None, height: int | None = None, seed: int = 0,
                 max_samples: int = MAX_SAMPLES, denoise: str | None = None,
                 samples: int | None = None, style: str = DEFAULT_STYLE):
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
                          style_class(style).default_inner, samples_given=samples is not None)
        self.budget = split(request, max(1, max_samples // (self.width * self.height)))
        self.inner, self.spp = int(self.budget.inner[0]), self.budget.spp
        # the render pipeline's scene and integrator: the scene's own max_depth, rr_depth and
        # hide_emitters kept; one pass is the whole film at 1 spp
        job = Job(scene=scene, width=w, height=h, spp=self.spp, seed=seed,
                  given={"style": "identity", "inner_samples": self.inner})
        self.job = job.with_(lanes_per_pass=self.width * self.height)
        resolved = resolve(self.job, self.scene)
        if self.width * self.height * self.spp > max_samples:
            raise UsageError(f"{self.width}x{self.height} at {self.spp} spp is "
                             f"{self.width * self.height * self.spp} camera samples, over the "
                             f"preview's cap of {max_samples}; lower --spp or the size")
        self.integrator = resolved.integrator
        # every front end's default (`denoise.default`): the full passes' expectation denoised where
        # it applies
        from styletrace.denoise.default import method_for
        method, self.note = method_for(self.scene, self.integrator, denoise)
        if denoise == "image":
            raise UsageError("the preview restyles the expectation: denoise 'image' would hide "
                             "what the styles see; use expectation, auto or off")
        self.denoised = method == "expectation" and denoise_available()
        full = (Expectation(FULL_QUALITY, label=self.label, coverage=0, max_samples=max_samples,
                            live=True) if self.denoised else
                Recorded(label=self.label, max_samples=max_samples))
        self.runner = Runner(resolved, InProcess(), full)
        draft_job = self.job.with_(given={**self.job.given, "inner_samples": DRAFT_INNER}, spp=1)
        self.draft_runner = Runner(resolve(draft_job, self.scene), InProcess(),
                                   Recorded(label=self.label, max_samples=max_samples))
        self.jit = threading.Lock()
        self._waiting = 0  # restyles waiting for `jit`: the render thread lets them first
        self._count = threading.Lock()
        self._draft_shown = threading.Event()
        self.buffer: Buffer | None = None
        self.draft: Buffer | None = None  # 1 spp, n = DRAFT_INNER; shown until the first full pass
        self.draft_denoised = False  # the draft holds a denoised expectation (the `denoise` extra)
        self.spp_done = 0
        self.error: str | None = None
        self.initial: dict[str, Any] = {"style": "cel", "params": {}}   # what the page starts with
        self.started = time.perf_counter()
        self.first_image_s: float | None = None
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._render, name="styletrace-preview-render",
                                        daemon=True)

    def start(self) -> "Session":
        self._thread.start()
        return self

    def stop(self) -> None:
        self._stop.set()
        self._draft_shown.set()
        self._thread.join(timeout=60)

    def _render(self) -> None:
        """The runs' passes, each under `jit`: the draft's first, then the full passes until
        stopped."""
        passes = self.runner.passes()
        try:
            if self.inner > DRAFT_INNER and not self._stop.is_set():
                draft = self.draft_runner.passes()
                with self.jit:
                    next(draft)
                    buf = self.draft_runner.finisher.recorded
                    # docs/denoise.md
                    self.draft_denoised = denoise_draft(buf, self.scene, self.seed)
                    self.draft = buf
                self._draft_shown.wait(DRAFT_GRACE_S)
            while not self._stop.is_set():
                self._yield_to_restyles()
                with self.jit:
                    prog = next(passes, None)
                    if prog is None:
                        return
                    # the buffer so far; where denoised, with D at every camera sample (the
                    # finisher's)
                    self.buffer = self.runner.finisher.recorded
                    self.spp_done = prog.spp_done
        except Exception as exc:  # shown on the page; the passes done stay usable
            self.error = first_line(exc)

    def _yield_to_restyles(self) -> None:
        """Wait while restyles are queued for the lock: a pass takes about a second, a restyle a few
        ms, and Python's lock is not fair (the render thread would take it again at once and starve
        the page)."""
        while self._waiting and not self._stop.is_set():
            time.sleep(0.002)

    @property
    def done(self) -> bool:
        return self.spp_done >= self.spp

    def restyle(self, style: str, estimator: str | None,
                params: dict[str, Any]) -> tuple[np.ndarray, int, int]:
        """The current buffer (or the draft before the first full pass) restyled.

        Args:
            style: the style's name. params: its parameters, {name: value}.
            estimator: the estimator's name (None: the recorded one where it applies).

        Returns:
            (the image, H x W x 3, or None before the draft finished; its spp; its n children).

        Raises:
            StyletraceError: a refused style, estimator or value (one line).
        """
        with self._count:
            self._waiting += 1
        try:
            return self._restyle(style, estimator, params)
        finally:
            with self._count:
                self._waiting -= 1

    def _restyle(self, style: str, estimator: str | None,
                 params: dict[str, Any]) -> tuple[np.ndarray, int, int]:
        with self.jit:
            buf = self.buffer if self.buffer is not None else self.draft
            if buf is None:
                return None, 0, 0
            img = restyle(buf, style=style, estimator=estimator, **params)
            if buf is self.draft:
                self._draft_shown.set()
            if self.first_image_s is None:
                self.first_image_s = time.perf_counter() - self.started
            return img, buf.spp, int(buf.header["slots"][0]["inner"])

    def state(self) -> dict[str, Any]:
        filtered = self.buffer is not None and self.buffer.filtered
        per = bytes_per_sample("first_hit", filtered=filtered)
        return {"scene": self.label, "width": self.width, "height": self.height,
                "spp_done": self.spp_done, "spp": self.spp, "inner": self.inner,
                "samples": self.width * self.height * self.spp_done,
                "cap_samples": self.max_samples, "bytes_per_sample": per,
                "bytes": self.width * self.height * self.spp_done * per, "error": self.error,
                "draft": self.buffer is None and self.draft is not None,
                "draft_denoised": self.buffer is None and self.draft_denoised,
                "denoised": self.denoised, "note": self.note,
                "initial": self.initial}

    def command(self, style: str, estimator: str | None, params: dict[str, Any],
                spp: int | None = None, inner: int | None = None) -> str:
        """The `styletrace render` command line that renders what the page shows.

        Args:
            style, estimator, params: what the page shows.
            spp, inner: those of the image shown (the draft's: 1 and DRAFT_INNER), or None: the
                session's.

        Returns:
            The command line, quoted for a shell.
        """
        import shlex
        words = ["styletrace", "render", self.label, "--style", style,
                 "--inner", str(inner or self.inner), "--spp", str(spp or self.spp),
                 "--seed", str(self.seed), "--pass-spp", "1"]
        if estimator:
            words += ["--estimator", estimator]
        if self.draft_denoised and (spp, inner) == (1, DRAFT_INNER):  # the denoised draft's image
            words += ["--denoise", "expectation", "--coverage", "0",
                      "--denoise-quality", DRAFT_QUALITY]
        elif self.denoised:  # the full passes' denoised expectation, styled at the camera samples
            words += ["--denoise", "expectation", "--coverage", "0",
                      "--denoise-quality", FULL_QUALITY]
        else:
            words += ["--denoise", "off"]
        if self.size[0]:
            words += ["--width", str(self.width), "--height", str(self.height)]
        for k, v in params.items():
            words += ["--set", f"{k}={v}"]
        return shlex.join(words + ["-o", "render.png"])


__all__ = ["Session"]
