"""The preview's JSON API: styles from the registry, restyles, saves, bad requests, concurrent
clients."""
import base64
import json
import threading

import numpy as np
import pytest
from starlette.testclient import TestClient

from styletrace.gate import mi
from styletrace.images import srgb8
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


def test_state_reports_the_split_and_the_cap(client, session):
    """`samples` are paths per pixel (2 camera samples x 2 children); the buffer counts camera
    samples."""
    st = client.get("/api/state").json()
    assert (st["samples"], st["spp"], st["children"], st["spp_done"]) == (4, 2, 2, 2)
    assert st["camera_samples"] == 48 * 40 * 2 and st["bytes"] == st["camera_samples"] * 65
    assert st["bytes_per_camera_sample"] == 65
    assert st["cap_camera_samples"] == session.job.cap
    assert st["method"] == "off" and st["done"] and not st["draft"] and st["kind"] == "final"


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
    assert full["version"] == session.state()["version"] == len(session.frames)


def test_a_quick_restyle_does_not_wait_for_a_pass(client, session):
    """While a pass holds the session's lock (held here by the test), a quick restyle answers at
    once, busy, with no image of its own (the render thread restyles its style after its pass:
    test_schedule.py)."""
    params = {"c": "1.3", "pivot": "auto", "exposure": "auto"}
    busy = session.counts["busy"]
    with session.schedule.turns:
        body = client.post("/api/restyle", json={"style": "contrast", "params": params,
                                                 "quick": True}).json()
        bad = client.post("/api/restyle", json={"style": "contrast", "params": {"c": "-1"},
                                                "quick": True})
    assert body["busy"] and session.counts["busy"] == busy + 1 and body["ms"] >= 0
    # a bad value is refused at once, busy or not
    assert bad.status_code == 400 and "bad value" in bad.json()["error"]
    # the render thread has finished: nothing of this style restyled after a pass to show
    assert body["image"] is None and body["kind"] == "final" and session.state()["restyled"] == 0


@pytest.mark.parametrize("flag", ["quick", "wait", "format"])
def test_bad_flags(client, flag):
    r = client.post("/api/restyle", json={"style": "cel", flag: "yes"})
    assert r.status_code == 400 and f"bad {flag} 'yes'" in r.json()["error"]


def rgba(image):
    """An H x W x 3 linear image as the page draws it: sRGB 8-bit, alpha 255 (H x W x 4)."""
    out = np.full(image.shape[:2] + (4,), 255, dtype=np.uint8)
    out[..., :3] = srgb8(image)
    return out


def test_the_pages_restyles_are_raw_pixels(client, session):
    """`format: rgba8` (the page's): the restyle's pixels, 8-bit sRGB RGBA within one level of
    `images.srgb8`, rows from the top, and the JSON answer's fields in X-Restyle."""
    from styletrace.lookdev.slider import quick_restyle
    params = {"c": "2.1", "pivot": "auto", "exposure": "auto"}
    r = client.post("/api/restyle", json={"style": "contrast", "params": params, "quick": True,
                                          "format": "rgba8"})
    meta = json.loads(r.headers["x-restyle"])
    assert r.status_code == 200 and r.headers["content-type"] == "application/octet-stream"
    assert (meta["width"], meta["height"]) == (48, 40) and len(r.content) == 48 * 40 * 4
    assert meta["quick"] and not meta["busy"] and meta["kind"] == "final" and meta["spp"] == 2
    assert meta["ms"] >= meta["restyle_ms"] > 0
    assert "--style contrast" in meta["command"] and "--set c=2.1" in meta["command"]
    got = np.frombuffer(r.content, dtype=np.uint8).reshape(40, 48, 4)
    want = rgba(quick_restyle(session.buffer, style="contrast", **params))
    assert np.abs(got.astype(int) - want).max() <= 1
    assert (got == want).mean() > 0.99  # the table's rounding differs only at a level's edge
    # the whole buffer, as the JSON answer's PNG holds it
    r = client.post("/api/restyle", json={"style": "contrast", "params": params,
                                          "format": "rgba8"})
    got = np.frombuffer(r.content, dtype=np.uint8).reshape(40, 48, 4)
    want = rgba(restyle(session.buffer, style="contrast", **params))
    assert not json.loads(r.headers["x-restyle"])["quick"]
    assert np.abs(got.astype(int) - want).max() <= 1


def test_rgba8_bounds_and_nan():
    """Out of [0, 1] is clamped, NaN is black, as `images.srgb8` has them."""
    from styletrace.preview.server import rgba8
    image = np.array([[[-1.0, 0.0, 0.5], [np.nan, 1.0, 7.0], [0.002, 0.02, 0.2]]],
                     dtype=np.float32)
    got = np.frombuffer(rgba8(image), dtype=np.uint8).reshape(1, 3, 4)
    assert got[0, :2].tolist() == [[0, 0, 188, 255], [0, 255, 255, 255]]
    assert np.abs(got.astype(int) - rgba(image)).max() <= 1


def test_a_busy_raw_restyle_without_an_image_is_a_204(client, session):
    """A busy answer with nothing restyled for its style: no pixels, its fields in X-Restyle."""
    with session.schedule.turns:
        r = client.post("/api/restyle", json={"style": "hatching", "quick": True,
                                              "format": "rgba8"})
    meta = json.loads(r.headers["x-restyle"])
    assert r.status_code == 204 and r.content == b"" and meta["busy"]
