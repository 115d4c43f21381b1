import contextlib
import shlex
import threading
import time

import numpy as np
import pytest

import styletrace

styletrace.init()  # the preview renders: pick the backend and register the plugins first

#: the longest a test waits for a session's render thread (a stuck thread, not a speed claim)
JOIN_S = 600


def wait_until(predicate, timeout, what):
    """Poll `predicate` until true; a functional timeout (a stuck session), not a speed claim."""
    end = time.monotonic() + timeout
    while not predicate():
        if time.monotonic() > end:
            raise AssertionError(f"timed out after {timeout} s waiting for {what}")
        time.sleep(0.05)


def finished(job, on_image=None):
    """A session of `job` whose schedule has run to its end: joined (a functional timeout for a
    stuck thread, not a speed claim)."""
    from styletrace.preview.session import Session
    s = Session(job, on_image=on_image).start()
    s.join(JOIN_S)
    assert s.done and s.error is None, s.error
    return s


def run_command(command, tmp_path):
    """`styletrace render` of a page's command line, in process, written as EXR: its image."""
    words = shlex.split(command)
    assert words[:2] == ["styletrace", "render"] and words[-2:] == ["-o", "render.png"]
    out = str(tmp_path / "render.exr")
    from styletrace.frontends import cli  # here: after styletrace.init() above
    from styletrace.gate import mi
    assert cli.main(words[1:-2] + ["-q", "-o", out]) == 0
    return np.array(mi.Bitmap(out), dtype=np.float32)[..., :3]


@contextlib.contextmanager
def served(session):
    """The preview app of `session` served by uvicorn on 127.0.0.1 (a free port) in a thread;
    yields its URL."""
    import uvicorn

    from styletrace.preview.server import make_app

    srv = uvicorn.Server(
        uvicorn.Config(make_app(session), host="127.0.0.1", port=0, log_level="warning")
    )
    thread = threading.Thread(target=srv.run, daemon=True)
    thread.start()
    wait_until(lambda: srv.started, 30, "the server")
    try:
        yield f"http://127.0.0.1:{srv.servers[0].sockets[0].getsockname()[1]}/"
    finally:
        srv.should_exit = True
        thread.join(timeout=10)


@pytest.fixture(scope="module")
def session():
    """A small finished preview session: the Cornell box at 48 x 40, 2 camera samples of 2
    children (2 passes), undenoised (the suite's $STYLETRACE_DENOISE)."""
    from styletrace.preview.jobs import page_job
    s = finished(page_job("cornell-box", inner=2, spp=2, width=48, height=40))
    yield s
    s.stop()


@pytest.fixture(scope="module")
def server(session):
    """The module's session served; yields its URL."""
    with served(session) as url:
        yield url
