import threading
import time

import pytest

import styletrace

styletrace.init()  # the preview renders: pick the backend and register the plugins first


def wait_until(predicate, timeout, what):
    end = time.monotonic() + timeout
    while not predicate():
        if time.monotonic() > end:
            raise AssertionError(f"timed out after {timeout} s waiting for {what}")
        time.sleep(0.05)


@pytest.fixture(scope="module")
def session():
    """A small preview session whose background render has finished (2 passes of 1 spp)."""
    from styletrace.preview.session import Session
    s = Session("cornell-box", inner=2, spp=2, width=48, height=40).start()
    wait_until(lambda: s.done or s.error, 120, "the background render")
    assert s.error is None
    yield s
    s.stop()


@pytest.fixture(scope="module")
def server(session):
    """The preview app served by uvicorn on 127.0.0.1 (a free port) in a thread; yields its URL."""
    import uvicorn

    from styletrace.preview.server import make_app

    srv = uvicorn.Server(
        uvicorn.Config(make_app(session), host="127.0.0.1", port=0, log_level="warning")
    )
    thread = threading.Thread(target=srv.run, daemon=True)
    thread.start()
    wait_until(lambda: srv.started, 30, "the server")
    yield f"http://127.0.0.1:{srv.servers[0].sockets[0].getsockname()[1]}/"
    srv.should_exit = True
    thread.join(timeout=10)
