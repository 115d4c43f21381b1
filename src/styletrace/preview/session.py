"""One preview session: a scene, a growing expectation buffer rendered in the background, restyles of it.

The background thread records the buffer pass by pass (1 spp per pass, `lookdev.record`) with the
`identity` style and n children per camera sample, so every style that needs children can restyle it;
after each pass the page's next restyle shows the refined image. Dr.Jit work of both threads (a render
pass, a restyle) runs under one lock, `jit`: requests from several browsers are served one at a time and
never see a buffer half appended. The buffer is capped (`MAX_SAMPLES` camera samples; the page says so).
"""
from __future__ import annotations

import threading
import time
from typing import Any

from ..jit import backend

backend()

import numpy as np  # noqa: E402

from .. import api  # noqa: E402
from ..errors import UsageError  # noqa: E402
from ..lookdev.buffer import MAX_SAMPLES, Buffer, bytes_per_sample  # noqa: E402
from ..lookdev.record import record, scene_label  # noqa: E402
from ..lookdev.restyle import restyle  # noqa: E402

DEFAULT_SIZE, DEFAULT_SPP, DEFAULT_INNER = 256, 16, 8


class Session:
    def __init__(self, scene: Any = None, inner: int | None = None, spp: int | None = None, width: int | None = None,
                 height: int | None = None, seed: int = 0, max_samples: int = MAX_SAMPLES):
        self.label = scene_label(scene)
        builtin = isinstance(scene, str) and not scene.lower().endswith(".xml") or scene is None
        w = width or (DEFAULT_SIZE if builtin else None)
        h = height or (DEFAULT_SIZE if builtin else None)
        self.size = (w, h)
        self.scene = api.load_scene(scene, w, h)
        self.inner = int(inner or DEFAULT_INNER)
        self.spp = int(spp or DEFAULT_SPP)
        self.seed = seed
        self.max_samples = max_samples
        film = self.scene.sensors()[0].film().crop_size()
        self.width, self.height = int(film[0]), int(film[1])
        if self.width * self.height * self.spp > max_samples:
            raise UsageError(f"{self.width}x{self.height} at {self.spp} spp is {self.width * self.height * self.spp} "
                             f"camera samples, over the preview's cap of {max_samples}; lower --spp or the size")
        self.integrator = api.make_integrator("identity", inner=self.inner)
        self.jit = threading.Lock()
        self.buffer: Buffer | None = None
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
        self._thread.join(timeout=60)

    def _render(self) -> None:
        passes = record(self.scene, self.integrator, self.spp, self.seed, self.label, self.max_samples,
                        lanes_per_pass=self.width * self.height)
        try:
            while not self._stop.is_set():
                with self.jit:
                    step = next(passes, None)
                    if step is None:
                        return
                    prog, self.buffer = step
                    self.spp_done = prog.spp_done
        except Exception as exc:  # shown on the page; the passes done stay usable
            self.error = api.first_line(exc)

    @property
    def done(self) -> bool:
        return self.spp_done >= self.spp

    def restyle(self, style: str, estimator: str | None, params: dict[str, Any]) -> tuple[np.ndarray, int]:
        """The current buffer restyled (and its spp); None image before the first pass finished."""
        with self.jit:
            if self.buffer is None:
                return None, 0
            img = restyle(self.buffer, style=style, estimator=estimator, **params)
            if self.first_image_s is None:
                self.first_image_s = time.perf_counter() - self.started
            return img, self.spp_done

    def state(self) -> dict[str, Any]:
        per = bytes_per_sample("first_hit")
        return {"scene": self.label, "width": self.width, "height": self.height, "spp_done": self.spp_done,
                "spp": self.spp, "inner": self.inner, "samples": self.width * self.height * self.spp_done,
                "cap_samples": self.max_samples, "bytes_per_sample": per,
                "bytes": self.width * self.height * self.spp_done * per, "error": self.error,
                "initial": self.initial}

    def command(self, style: str, estimator: str | None, params: dict[str, Any]) -> str:
        """The `styletrace render` command line that renders what the page shows."""
        import shlex
        words = ["styletrace", "render", self.label, "--style", style, "--inner", str(self.inner),
                 "--spp", str(self.spp), "--seed", str(self.seed), "--pass-spp", "1"]
        if estimator:
            words += ["--estimator", estimator]
        if self.size[0]:
            words += ["--width", str(self.width), "--height", str(self.height)]
        for k, v in params.items():
            words += ["--set", f"{k}={v}"]
        return shlex.join(words + ["-o", "render.png"])


__all__ = ["Session"]
