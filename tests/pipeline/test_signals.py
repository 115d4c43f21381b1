"""Ctrl-C and SIGTERM during a run (`pipeline.signals.StopSignals`), without a clock: the pass
under way is this test's thread, which never finishes by itself; the watcher abandons it after the
grace period (set to none here, so that no time passes in the test) or at a second signal (the
grace period set to a day). The command line's end-to-end run: tests/frontends/test_cli.py."""
import os
import signal
import threading

import pytest

from styletrace.pipeline.signals import StopSignals


@pytest.fixture(autouse=True)
def handlers():
    """This process's handlers back after each test (a stopped run leaves the signals ignored,
    on purpose, for the interpreter's shutdown)."""
    old = {s: signal.getsignal(s) for s in StopSignals.SIGNALS}
    yield
    for s, handler in old.items():
        signal.signal(s, handler)


def interrupted(monkeypatch, grace: float, signals: list[int]) -> list[int]:
    """Send `signals` to this process inside `StopSignals`, the pass under way never finishing:
    the signal numbers the watcher abandoned with."""
    monkeypatch.setattr(StopSignals, "GRACE", grace)
    abandoned, called = [], threading.Event()

    def abandon(signum):
        abandoned.append(signum)
        called.set()

    with StopSignals(abandon) as stop:
        for s in signals:
            os.kill(os.getpid(), s)
        # the pass under way: it waits for the watcher, which must not wait for it (a functional
        # timeout, far beyond any machine's signal delivery)
        assert called.wait(120), "the watcher waited for the pass under way"
        assert stop.count == len(signals) and stop.exit_status == 128 + signals[0]
    return abandoned


def test_one_signal_abandons_a_pass_that_outlasts_the_grace_period(monkeypatch):
    assert interrupted(monkeypatch, 0.0, [signal.SIGTERM]) == [signal.SIGTERM]


def test_a_second_signal_abandons_at_once(monkeypatch):
    assert interrupted(monkeypatch, 86400.0, [signal.SIGINT, signal.SIGINT]) == [signal.SIGINT]


def test_a_settled_run_is_not_abandoned(monkeypatch):
    """The loop got to its write first (`settled`): the watcher leaves it alone."""
    monkeypatch.setattr(StopSignals, "GRACE", 0.0)
    abandoned = []
    with StopSignals(abandoned.append) as stop:
        with stop.lock:
            stop.settled = True
        os.kill(os.getpid(), signal.SIGTERM)
        done = threading.Event()
        watcher = [t for t in threading.enumerate() if t.name == "styletrace-signals"]
        threading.Thread(target=lambda: ([t.join(120) for t in watcher], done.set())).start()
        assert done.wait(180)
    assert abandoned == [] and stop.count == 1
