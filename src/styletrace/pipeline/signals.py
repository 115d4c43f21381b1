"""Ctrl-C (SIGINT) and SIGTERM during a run that writes a file (`StopSignals`), its passes and
progress bar (`Passes`), and `say`, its one-line messages on stderr. `pipeline.runner.Runner.write`
uses them.
"""
from __future__ import annotations

import os
import select
import signal
import sys
import threading
import time


def one_line(text: str) -> str:
    """A message as one line: newlines and carriage returns (say, in a file name) escaped.

    Args:
        text: the message (any object: its str).

    Returns:
        The text with each carriage return and newline written as its escape sequence.
    """
    return str(text).replace("\r", "\\r").replace("\n", "\\n")


def say(message: str) -> None:
    """Print a message to stderr as one line (`one_line`), flushed.

    Args:
        message: the message.
    """
    print(one_line(message), file=sys.stderr, flush=True)


class StopSignals:
    """Ctrl-C (SIGINT) and SIGTERM during a render (a context manager that installs the handlers).

    The first signal asks the pass loop to stop after the pass under way. If that pass has not
    finished `GRACE` seconds later, or a second signal comes, a watcher thread calls
    `abandon(signum)`, which writes the finished passes without Mitsuba and ends the process. Exit
    status: 128 + the signal's number (130 for Ctrl-C, 143 for SIGTERM).
    Design: docs/design/stopping_a_render.md.

    Args:
        abandon: called from the watcher thread with the signal's number, under `lock`; it ends the
            process (`os._exit`).
    """

    GRACE = 1.0
    SIGNALS = (signal.SIGINT, signal.SIGTERM)

    def __init__(self, abandon):
        self._abandon = abandon
        self.signum = 0  # the first signal received, 0 if none
        self.count = 0
        # held by the loop while it settles, by the watcher while it abandons
        self.lock = threading.Lock()
        self.settled = False

    def __enter__(self):
        self._r, self._w = os.pipe()
        os.set_blocking(self._w, False)
        self._old = {s: signal.signal(s, lambda *_: None) for s in self.SIGNALS}
        self._old_fd = signal.set_wakeup_fd(self._w)
        threading.Thread(target=self._watch, daemon=True, name="styletrace-signals").start()
        return self

    @property
    def exit_status(self) -> int:
        return 128 + self.signum

    def _watch(self):
        deadline = None
        while True:
            timeout = None if deadline is None else max(0.0, deadline - time.monotonic())
            ready, _, _ = select.select([self._r], [], [], timeout)
            if not ready:  # the grace period is over and the pass still runs
                return self._give_up()
            data = os.read(self._r, 64)
            if not data:  # closed by __exit__
                os.close(self._r)
                return None
            for signum in (b for b in data if b in self.SIGNALS):
                self.count += 1
                if self.count == 1:
                    self.signum = signum
                    deadline = time.monotonic() + self.GRACE
                    say(f"styletrace: {signal.Signals(signum).name}: stopping after this pass "
                        f"(at most {self.GRACE:g} s; again to stop now)")
                else:
                    return self._give_up()

    def _give_up(self):
        with self.lock:
            if self.settled:  # the loop got there first and is writing
                return
            self._abandon(self.signum)

    def __exit__(self, *exc):
        signal.set_wakeup_fd(self._old_fd)
        for s, handler in self._old.items():
            # after a stop the render is saved and the exit status decided: a second Ctrl-C during
            # the interpreter's shutdown (which restores the default handlers) must not turn it into
            # a kill
            signal.signal(s, signal.SIG_IGN if self.count else handler)
        os.close(self._w)
        return False


class Passes:
    """The passes of a command-line render as they finish.

    `latest`: the last finished pass's progress (what an `abandon` of `StopSignals` writes);
    `failure`: the error of a later pass, which must not cost the finished ones; `bar`: a tqdm bar
    over the camera samples per pixel, or None.

    Args:
        spp: the render's camera samples per pixel (the bar's total).
        total: the number of passes (no bar for one). quiet: no bar.
    """

    def __init__(self, spp: int, total: int, quiet: bool):
        self.latest = self.failure = None
        self.bar = None
        if total > 1 and not quiet:
            from tqdm import tqdm
            # the first pass includes the kernel's compilation: the bar says so until it is done
            self.bar = tqdm(
                total=spp,
                unit="spp",
                desc=f"compiling and rendering pass 1 of {total}",
                file=sys.stderr,
            )

    def follow(self, source, stop: StopSignals) -> None:
        """Take the passes of `source` until it ends or `stop` has a signal.

        Args:
            source: an iterator of `Progress`. stop: the run's `StopSignals`.

        Raises:
            KeyboardInterrupt, RuntimeError: before a pass finished (after one, kept in `failure`).
        """
        try:
            for prog in source:
                if self.bar is not None:
                    if self.latest is None:
                        self.bar.set_description_str("rendering", refresh=False)
                    self.bar.update(prog.spp_done - (self.latest.spp_done if self.latest else 0))
                self.latest = prog
                if stop.count:
                    break
        except (KeyboardInterrupt, RuntimeError) as exc:
            if self.latest is None:
                raise
            self.failure = exc

    def close(self) -> None:
        if self.bar is not None:
            self.bar.close()


__all__ = ["StopSignals", "Passes", "say", "one_line"]
