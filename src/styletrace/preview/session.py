"""One preview session: a scene, a growing expectation buffer rendered in the background, restyles of it.

The background thread first records a **draft**: 1 spp with one child per camera sample (n = 1), a
fifth of a full pass's work (measured: 0.2 s against 1.1 s for the Cornell box at 256² with n = 8), so
the first image arrives early; restyles use it until the first full pass is done. With the `denoise`
extra the draft's expectation is denoised before the style (`denoise.draft`), so the draft looks clean. Then it records the
buffer pass by pass (1 spp per pass, `lookdev.record`), its expectation denoised after each pass where
every front end's default does (`denoise`: auto, expectation or off; `denoise.default`), with the `identity` style and n children per
camera sample, so every style that needs children can restyle it; after each pass the page's next
restyle shows the refined image. Dr.Jit work of both threads (a render
pass, a restyle) runs under one lock, `jit`: requests from several browsers are served one at a time and
never see a buffer half appended. The buffer is capped (`MAX_SAMPLES` camera samples; the page says so).
"""
from __future__ import annotations

import threading
import time
from typing import Any

import numpy as np

from styletrace.denoise.draft import QUALITY as DRAFT_QUALITY
from styletrace.denoise.draft import available as denoise_available
from styletrace.denoise.draft import draft as denoise_draft
from styletrace.denoise.expectation import attach
from styletrace.errors import UsageError
from styletrace.lookdev.buffer import MAX_SAMPLES, Buffer, bytes_per_sample
from styletrace.lookdev.record import record, scene_label
from styletrace.lookdev.restyle import restyle
from styletrace.pipeline.job import Job
from styletrace.pipeline.resolve import resolve
from styletrace.scene.loading import first_line

#: OIDN's quality on the full passes (the draft's is `denoise.draft.QUALITY`)
FULL_QUALITY = "high"

DEFAULT_SIZE, DEFAULT_SPP, DEFAULT_INNER = 256, 16, 8
DRAFT_INNER = 1  # children per camera sample of the draft pass
#: how long the render thread waits, after the draft, for a restyle to show it before the first full pass
#: takes the lock for about a second (the page polls every 0.3 s; measured: the first request can arrive
#: 0.2 s after the draft is done)
DRAFT_GRACE_S = 1.0


class Session:
    def __init__(self, scene: Any = None, inner: int | None = None, spp: int | None = None, width: int | None = None,
                 height: int | None = None, seed: int = 0, max_samples: int = MAX_SAMPLES, denoise: str | None = None):
        self.label = scene_label(scene)
        builtin = isinstance(scene, str) and not scene.lower().endswith(".xml") or scene is None
        w = width or (DEFAULT_SIZE if builtin else None)
        h = height or (DEFAULT_SIZE if builtin else None)
        self.size = (w, h)
        self.inner = int(inner or DEFAULT_INNER)
        # the render pipeline's scene and integrator: the scene's own max_depth, rr_depth and hide_emitters kept
        self.job = Job(scene=scene, width=w, height=h, given={"style": "identity", "inner_samples": self.inner},
                       spp=int(spp or DEFAULT_SPP), seed=seed)
        resolved = resolve(self.job)
        self.scene = resolved.scene
        self.spp = int(spp or DEFAULT_SPP)
        self.seed = seed
        self.max_samples = max_samples
        film = self.scene.sensors()[0].film().crop_size()
        self.width, self.height = int(film[0]), int(film[1])
        if self.width * self.height * self.spp > max_samples:
            raise UsageError(f"{self.width}x{self.height} at {self.spp} spp is {self.width * self.height * self.spp} "
                             f"camera samples, over the preview's cap of {max_samples}; lower --spp or the size")
        self.integrator = resolved.integrator
        # every front end's default (`denoise.default`): the full passes' expectation denoised where it applies
        from styletrace.denoise.default import method_for
        method, self.note = method_for(self.scene, self.integrator, denoise)
        if denoise == "image":
            raise UsageError("the preview restyles the expectation: denoise 'image' would hide what the styles see; "
                             "use expectation, auto or off")
        self.denoised = method == "expectation" and denoise_available()
        self._draft_integrator = resolve(self.job.with_(given={**self.job.given, "inner_samples": DRAFT_INNER}),
                                         self.scene).integrator
        self.jit = threading.Lock()
        self._waiting = 0                      # restyles waiting for `jit`: the render thread lets them first
        self._count = threading.Lock()
        self._draft_shown = threading.Event()
        self.buffer: Buffer | None = None
        self.draft: Buffer | None = None   # 1 spp, n = DRAFT_INNER; shown until the first full pass is done
        self.draft_denoised = False        # the draft holds a denoised expectation (the `denoise` extra)
        self.spp_done = 0
        self.error: str | None = None
        self.initial: dict[str, Any] = {"style": "cel", "params": {}}   # what the page starts with
        self.started = time.perf_counter()
        self.first_image_s: float | None = None
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._render, name="styletrace-preview-render", daemon=True)

    def start(self) -> "Session":
        self._thread.start()
        return self

    def stop(self) -> None:
        self._stop.set()
        self._draft_shown.set()
        self._thread.join(timeout=60)

    def _render(self) -> None:
        lanes = self.width * self.height
        passes = record(self.scene, self.integrator, self.spp, self.seed, self.label, self.max_samples,
                        lanes_per_pass=lanes)
        try:
            if self.inner > DRAFT_INNER and not self._stop.is_set():
                draft = record(self.scene, self._draft_integrator, 1, self.seed,
                               self.label, self.max_samples, lanes_per_pass=lanes)
                with self.jit:
                    _, buf = next(draft)
                    self.draft_denoised = denoise_draft(buf, self.scene, self.seed)  # docs/denoise.md
                    self.draft = buf
                self._draft_shown.wait(DRAFT_GRACE_S)
            while not self._stop.is_set():
                self._yield_to_restyles()
                with self.jit:
                    step = next(passes, None)
                    if step is None:
                        return
                    prog, buf = step
                    if self.denoised:  # D of the passes so far, at every camera sample (`denoise.expectation`)
                        attach(buf, self.scene, buf.spp, self.seed, FULL_QUALITY)
                    self.buffer = buf
                    self.spp_done = prog.spp_done
        except Exception as exc:  # shown on the page; the passes done stay usable
            self.error = first_line(exc)

    def _yield_to_restyles(self) -> None:
        """Wait while restyles are queued for the lock: a pass takes about a second, a restyle a few ms, and
        Python's lock is not fair (the render thread would take it again at once and starve the page)."""
        while self._waiting and not self._stop.is_set():
            time.sleep(0.002)

    @property
    def done(self) -> bool:
        return self.spp_done >= self.spp

    def restyle(self, style: str, estimator: str | None, params: dict[str, Any]) -> tuple[np.ndarray, int, int]:
        """The current buffer (or the draft before the first full pass) restyled, its spp and n; None image
        before the draft finished."""
        with self._count:
            self._waiting += 1
        try:
            return self._restyle(style, estimator, params)
        finally:
            with self._count:
                self._waiting -= 1

    def _restyle(self, style: str, estimator: str | None, params: dict[str, Any]) -> tuple[np.ndarray, int, int]:
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
        return {"scene": self.label, "width": self.width, "height": self.height, "spp_done": self.spp_done,
                "spp": self.spp, "inner": self.inner, "samples": self.width * self.height * self.spp_done,
                "cap_samples": self.max_samples, "bytes_per_sample": per,
                "bytes": self.width * self.height * self.spp_done * per, "error": self.error,
                "draft": self.buffer is None and self.draft is not None,
                "draft_denoised": self.buffer is None and self.draft_denoised,
                "denoised": self.denoised, "note": self.note,
                "initial": self.initial}

    def command(self, style: str, estimator: str | None, params: dict[str, Any], spp: int | None = None,
                inner: int | None = None) -> str:
        """The `styletrace render` command line that renders what the page shows (spp and n: the session's,
        or those of the image shown, e.g. the draft's)."""
        import shlex
        words = ["styletrace", "render", self.label, "--style", style, "--inner", str(inner or self.inner),
                 "--spp", str(spp or self.spp), "--seed", str(self.seed), "--pass-spp", "1"]
        if estimator:
            words += ["--estimator", estimator]
        if self.draft_denoised and (spp, inner) == (1, DRAFT_INNER):  # the denoised draft's image
            words += ["--denoise", "expectation", "--coverage", "0", "--denoise-quality", DRAFT_QUALITY]
        elif self.denoised:  # the full passes' denoised expectation, styled at the camera samples
            words += ["--denoise", "expectation", "--coverage", "0", "--denoise-quality", FULL_QUALITY]
        else:
            words += ["--denoise", "off"]
        if self.size[0]:
            words += ["--width", str(self.width), "--height", str(self.height)]
        for k, v in params.items():
            words += ["--set", f"{k}={v}"]
        return shlex.join(words + ["-o", "render.png"])


__all__ = ["Session"]
