"""What a long wait is for: one status line on stderr while a phase of `styletrace render` runs.

    status = Status()                       # Status(enabled=False) under -q
    with status.phase("loading scene dragon"):
        scene = load_scene("dragon")

A phase that ends within `delay` seconds (DELAY; $STYLETRACE_STATUS_DELAY sets it) shows nothing;
a longer one gets a tqdm line, `styletrace: loading scene dragon (3 s)`, from a timer thread,
redrawn every second on a terminal (drawn once more, with the final time, in a file or pipe).
The first pass is "compiling and rendering": its time includes the JIT compilation.
Design: docs/design/status_line.md.
"""
from __future__ import annotations

import contextlib
import os
import sys
import threading
import time
from typing import IO, Iterator

from styletrace.errors import UsageError

#: seconds a phase runs before its line appears
DELAY = 2.0
#: the environment variable that overrides DELAY (tests set 0 to see every phase)
DELAY_ENV = "STYLETRACE_STATUS_DELAY"


def delay_from_env() -> float:
    """DELAY, or the value of STYLETRACE_STATUS_DELAY (seconds, finite, >= 0).

    Raises:
        UsageError: a value that is not such a number.
    """
    text = os.environ.get(DELAY_ENV)
    if text is None or not text.strip():
        return DELAY
    try:
        value = float(text)
    except ValueError:
        value = float("nan")
    if not (0.0 <= value < float("inf")):
        raise UsageError(f"bad value {text!r} for {DELAY_ENV}: expected seconds, a number >= 0")
    return value


def _isatty(stream) -> bool:
    try:
        return bool(stream.isatty())
    except (AttributeError, ValueError):
        return False


class Status:
    """At most one phase at a time; `start` ends the phase under way before it begins the next.

    Args:
        enabled: show anything at all (False under -q).
        delay: seconds a phase runs before its line appears (None: `delay_from_env()`).
        stream: where the line goes (None: stderr).
    """

    def __init__(
        self, enabled: bool = True, delay: float | None = None, stream: IO[str] | None = None
    ):
        self.enabled = enabled
        self.delay = delay_from_env() if delay is None else delay
        self.stream = stream if stream is not None else sys.stderr
        self._done: threading.Event | None = None
        self._thread: threading.Thread | None = None

    def start(self, text: str) -> None:
        """Begin a phase, ending the one under way; its line appears after `delay` seconds.

        Args:
            text: what the phase does, e.g. "loading scene dragon".
        """
        self.stop()
        if not self.enabled:
            return
        done = threading.Event()
        self._done = done
        self._thread = threading.Thread(target=self._show, args=(text, done), daemon=True,
                                        name="styletrace-status")
        self._thread.start()

    def follow(self, bar) -> None:
        """A phase shown by a tqdm bar already on screen (the passes' bar): redrawn every second on
        a terminal, so that its time runs on while a long pass holds its count still.

        Args:
            bar: the tqdm bar.
        """
        self.stop()
        if not self.enabled or not _isatty(self.stream):
            return
        done = threading.Event()
        self._done = done

        def redraw():
            while not done.wait(1.0):
                bar.refresh()
        self._thread = threading.Thread(target=redraw, daemon=True, name="styletrace-status")
        self._thread.start()

    def stop(self) -> None:
        """End the phase: its line, if shown, is finished with the final time and a newline."""
        if self._done is None:
            return
        self._done.set()
        self._thread.join()
        self._done = self._thread = None

    @contextlib.contextmanager
    def phase(self, text: str) -> Iterator[None]:
        """The phase `text` for the duration of a `with` block (`start`, then `stop`).

        Args:
            text: what the phase does.
        """
        self.start(text)
        try:
            yield
        finally:
            self.stop()

    def _show(self, text: str, done: threading.Event) -> None:
        began = time.monotonic()
        if done.wait(self.delay):
            return
        from tqdm import tqdm
        tty = _isatty(self.stream)

        def now() -> str:  # the phase's own time, not the line's (which appears `delay` late)
            return f"{text} ({time.monotonic() - began:.0f} s)"

        line = tqdm(
            total=None,
            desc=now(),
            file=self.stream,
            bar_format="styletrace: {desc}",
            mininterval=0.0,
        )
        try:
            while not done.wait(1.0 if tty else None):
                line.set_description_str(now())
            line.set_description_str(now(), refresh=False)
        finally:
            line.close()


__all__ = ["Status", "DELAY", "DELAY_ENV", "delay_from_env"]
