"""The preview's JSON API: styles from the registry, restyles, saves, bad requests, concurrent
clients."""
import base64
import threading

import numpy as np
import pytest
from starlette.testclient import TestClient

from styletrace.gate import mi
from styletrace.lookdev.restyle import restyle
from styletrace.preview.server import make_app
from styletrace.styles import style_class, style_names


@pytest.fixture(scope="module")
def client(session):
    return TestClient(make_app(session))


def test_styles_come_from_the_registry(client):
    table = {s["name"]: s for s in client.get("/api/styles").json()["styles"]}
    assert set(table) == {n for n in style_names() if not style_class(n).per_sample}
    cel = {p["name"]: p for p in table["cel"]["params"]}
    assert (
        cel["levels"]["kind"] == "floats"
        and cel["levels"]["low"] == 0.0
        and cel["levels"]["default"] == "auto"
    )
    assert cel["bands"]["default"] == "3"
    assert table["contrast"]["estimators"] == ["direct", "affine"]
    assert "gradient" in {p["kind"] for p in table["color_map"]["params"]}


def test_state_reports_the_cap(client, session):
    st = client.get("/api/state").json()
    assert (
        st["spp_done"] == 2 and st["samples"] == 48 * 40 * 2 and st["bytes"] == st["samples"] * 65
    )
    assert st["cap_samples"] == session.max_camera_samples


def test_save_exr_is_the_restyle(client, session):
    r = client.post(
        "/api/save", json={"style": "gamma", "params": {"gamma": "1.8"}, "format": "exr"}
    )
    assert r.status_code == 200 and r.headers["content-type"] == "image/x-exr"
    got = _read_exr(r.content)
    np.testing.assert_array_equal(got, restyle(session.buffer, style="gamma", gamma=1.8))


def _read_exr(data):
    import os
    import tempfile
    fd, path = tempfile.mkstemp(suffix=".exr")
    with os.fdopen(fd, "wb") as f:
        f.write(data)
    try:
        return np.array(mi.Bitmap(path), dtype=np.float32)
    finally:
        os.unlink(path)


def test_restyle_returns_a_png_and_the_command(client):
    r = client.post("/api/restyle", json={"style": "cel", "params": {"levels": "0.1,0.9"}})
    body = r.json()
    assert r.status_code == 200 and body["spp"] == 2
    assert base64.b64decode(body["image"].split(",", 1)[1])[:8] == b"\x89PNG\r\n\x1a\n"
    assert body["command"].startswith(
        "styletrace render cornell-box --style cel --inner 2 --spp 2 --seed 0 --pass-spp 1"
    )
    assert "--set levels=0.1,0.9" in body["command"]


@pytest.mark.parametrize(
    "body,status,message",
    [
        ({"style": "nope"}, 400, "bad style 'nope'"),
        (
            {"style": "cel", "params": {"levels": "0.1,0.5", "thresholds": "0.3,0.6"}},
            400,
            "expected 3 levels for 2 thresholds",
        ),
        ({"style": "cel", "params": {"nope": "1"}}, 400, "unknown property 'nope'"),
        ({"style": "gamma", "estimator": "series"}, 400, "estimator 'series' cannot restyle"),
        ({"style": "cel", "params": ["x"]}, 400, "bad params"),
        ("not an object", 400, "must be a JSON object"),
    ],
)
def test_bad_requests_get_a_4xx_with_a_message(client, body, status, message):
    r = client.post("/api/restyle", json=body)
    assert r.status_code == status and message in r.json()["error"]


def test_bad_save_format(client):
    r = client.post("/api/save", json={"style": "cel", "format": "jpg"})
    assert r.status_code == 400 and "bad format 'jpg'" in r.json()["error"]


def test_two_clients_at_once_get_consistent_images(session):
    """Two clients restyle different styles concurrently; each gets exactly its own style's
    image."""
    styles = {"cel": {}, "color_map": {"gradient": "heat"}}
    want = {s: restyle(session.buffer, style=s, **p) for s, p in styles.items()}
    errors = []

    def worker(style):
        client = TestClient(make_app(session))
        for _ in range(4):
            r = client.post(
                "/api/save", json={"style": style, "params": styles[style], "format": "exr"}
            )
            if r.status_code != 200 or not np.array_equal(_read_exr(r.content), want[style]):
                errors.append(style)

    threads = [threading.Thread(target=worker, args=(s,)) for s in styles]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert errors == []


def _png_of(image):
    from styletrace.preview.server import encode_image_file
    return "data:image/png;base64," + base64.b64encode(encode_image_file(image, "png")).decode()


def test_quick_restyles_one_point_per_pixel_and_the_full_one_the_buffer(client, session):
    from styletrace.lookdev.slider import quick_restyle
    params = {"c": "1.7", "pivot": "auto", "exposure": "auto"}
    quick = client.post("/api/restyle", json={"style": "contrast", "params": params,
                                              "quick": True}).json()
    assert quick["quick"] and not quick["busy"] and quick["kind"] == "final"
    assert quick["image"] == _png_of(quick_restyle(session.buffer, style="contrast", **params))
    full = client.post("/api/restyle", json={"style": "contrast", "params": params,
                                             "wait": False}).json()
    assert not full["quick"] and not full["busy"] and full["stamp"] > quick["stamp"]
    assert full["image"] == _png_of(restyle(session.buffer, style="contrast", **params))
    assert full["image"] != quick["image"]
    assert full["version"] == session.state()["version"] == len(session.shown)


def test_a_quick_restyle_does_not_wait_for_a_pass(client, session):
    """While a pass holds the session's lock (held here by the test), a quick restyle answers at
    once, busy, with no image of its own (the render thread restyles its style after its pass:
    test_schedule.py)."""
    params = {"c": "1.3", "pivot": "auto", "exposure": "auto"}
    busy = session.counts["busy"]
    with session.jit:
        body = client.post("/api/restyle", json={"style": "contrast", "params": params,
                                                 "quick": True}).json()
        bad = client.post("/api/restyle", json={"style": "contrast", "params": {"c": "-1"},
                                                "quick": True})
    assert body["busy"] and session.counts["busy"] == busy + 1
    # a bad value is refused at once, busy or not
    assert bad.status_code == 400 and "bad value" in bad.json()["error"]
    # the render thread has finished: nothing of this style restyled after a pass to show
    assert body["image"] is None and body["kind"] == "final" and session.state()["restyled"] == 0


@pytest.mark.parametrize("flag", ["quick", "wait"])
def test_bad_flags(client, flag):
    r = client.post("/api/restyle", json={"style": "cel", flag: "yes"})
    assert r.status_code == 400 and f"bad {flag} 'yes'" in r.json()["error"]
