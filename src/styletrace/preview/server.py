"""`styletrace preview`: a local web page to tune a style live (Starlette app, served by uvicorn).

Routes (JSON API documented in docs/preview.md):
    GET  /              the page (page.html)
    GET  /api/styles    the style registry: every style's parameters (kind, default, range, choices)
                        and the estimators that can restyle it
    GET  /api/state     the background render: samples (paths per pixel), spp done / to do, camera
                        samples recorded, buffer bytes and cap
    POST /api/restyle   {"style", "params", "estimator", "quick", "wait", "format"}
                        -> "json": {"image": PNG data URL or null, "spp", "draft", "ms",
                            "restyle_ms", "command", "quick", "busy", "stamp", "version",
                            "kind", "label"}; "rgba8": the pixels, 8-bit sRGB RGBA, the other
                            fields in the header X-Restyle (204 without an image)
    POST /api/save      {"style", "params", "estimator", "format": "png"|"exr"} -> the image file
A bad request gets a 4xx with {"error": one line}. The server listens on 127.0.0.1 only.
"""
from __future__ import annotations

import base64
import json
import os
import sys
import tempfile
import time
from typing import Any

import numpy as np

from styletrace.errors import StyletraceError, UsageError

PAGE = os.path.join(os.path.dirname(__file__), "page.html")
#: the answers of /api/restyle: a PNG data URL in JSON, or the raw pixels (the page's)
FORMATS = ("json", "rgba8")


def styles_table() -> list[dict[str, Any]]:
    from styletrace.config.estimator_registry import MEAN_ESTIMATORS, applicable
    from styletrace.styles import style_class, style_names
    out = []
    for name in style_names():
        cls = style_class(name)
        if cls.per_sample:
            continue  # cannot restyle (a buffer keeps the children's mean)
        style = cls()
        out.append(
            {
                "name": name,
                "summary": cls.summary,
                "closed_form": style.closed_form,
                "estimators": [e for e in applicable(style) if e in MEAN_ESTIMATORS],
                "params": [
                    {
                        "name": p.name,
                        "kind": p.kind,
                        "default": p.show(style.values[p.name]),
                        "doc": p.doc,
                        "low": p.low,
                        "high": p.high,
                        "low_open": p.low_open,
                        "choices": list(p.choices),
                        "allowed": p.allowed(),
                    }
                    for p in cls.params
                ],
            }
        )
    return out


def encode_image_file(image, fmt: str) -> bytes:
    """The image as the bytes of a .png (sRGB 8-bit) or .exr (linear float32) file, written by
    `images.write_image` through a temporary file.

    Args:
        image: H x W x 3, linear. fmt: "png" or "exr".

    Returns:
        The file's bytes.
    """
    from styletrace.images import write_image
    fd, tmp = tempfile.mkstemp(suffix="." + fmt)
    os.close(fd)
    try:
        write_image(image, tmp)
        with open(tmp, "rb") as f:
            return f.read()
    finally:
        os.unlink(tmp)


def rgba8(image) -> bytes:
    """The image as the page's canvas takes it (`ImageData`): 8-bit sRGB (`images.srgb8`), RGBA,
    rows from the top.

    Args:
        image: H x W x 3, linear (NaN as 0, clamped to [0, 1]).

    Returns:
        H * W * 4 bytes, alpha 255.
    """
    from styletrace.images import srgb8
    x = np.asarray(image, dtype=np.float32)[..., :3]
    out = np.full(x.shape[:2] + (4,), 255, dtype=np.uint8)
    out[..., :3] = srgb8(x)
    return out.tobytes()


def restyle_headers(meta: dict[str, Any], start: float) -> dict[str, str]:
    """The headers of an `rgba8` answer: X-Restyle, the JSON answer's fields but the image (ASCII
    JSON), with `ms` the server's time since `start` (`time.perf_counter`)."""
    return {"X-Restyle": json.dumps({**meta, "ms": (time.perf_counter() - start) * 1e3}),
            "Cache-Control": "no-store"}


def make_app(session):
    """The Starlette app of a session: the routes of the module doc.

    Args:
        session: the `preview.session.Session` to serve.

    Returns:
        The app; a bad request gets a 4xx with {"error": one line}, a restyle or save before the
        first image a 409.
    """
    from starlette.applications import Starlette
    from starlette.concurrency import run_in_threadpool
    from starlette.requests import Request
    from starlette.responses import FileResponse, JSONResponse, Response
    from starlette.routing import Route

    table = styles_table()
    known = {s["name"] for s in table}

    def bad(message: str, status: int = 400) -> JSONResponse:
        return JSONResponse({"error": message}, status_code=status)

    async def parse(request: Request) -> tuple[str, str | None, dict[str, Any]]:
        try:
            body = await request.json()
        except Exception:
            raise ValueError("the request body must be JSON") from None
        if not isinstance(body, dict):
            raise ValueError("the request body must be a JSON object")
        style = body.get("style")
        if not isinstance(style, str) or style not in known:
            raise ValueError(f"bad style {style!r}: expected one of {', '.join(sorted(known))}")
        params = body.get("params") or {}
        if not isinstance(params, dict) or not all(
            isinstance(v, (str, int, float, bool)) for v in params.values()
        ):
            raise ValueError(
                "bad params: expected an object of name -> value (string, number or boolean)"
            )
        estimator = body.get("estimator") or None
        if estimator is not None and not isinstance(estimator, str):
            raise ValueError(f"bad estimator {estimator!r}: expected a name")
        return style, estimator, {str(k): v for k, v in params.items()}

    async def flags(request: Request) -> tuple[bool, bool, str]:
        """The restyle's `quick` (default false), `wait` (default: not quick) and `format`
        (default json)."""
        body = await request.json()
        quick = body.get("quick", False)
        wait = body.get("wait", not quick)
        for name, value in (("quick", quick), ("wait", wait)):
            if not isinstance(value, bool):
                raise ValueError(f"bad {name} {value!r}: expected true or false")
        fmt = body.get("format", "json")
        if fmt not in FORMATS:
            raise ValueError(f"bad format {fmt!r}: expected {' or '.join(FORMATS)}")
        return quick, wait, fmt

    def styled(style, estimator, params, quick, wait, fmt):
        """`session.styled`, and its image as `rgba8` bytes for that format (else None): a quick
        restyle's pixels as the session encoded them on the device, else `rgba8`'s."""
        r = session.styled(style, estimator, params, quick, wait)
        if fmt != "rgba8" or r.image is None:
            return r, None
        return r, r.pixels.tobytes() if r.pixels is not None else rgba8(r.image)

    async def page(request):
        return FileResponse(PAGE, media_type="text/html")

    async def styles(request):
        return JSONResponse({"styles": table})

    async def state(request):
        return JSONResponse(session.state())

    async def do_restyle(request: Request):
        t = time.perf_counter()
        try:
            style, estimator, params = await parse(request)
            quick, wait, fmt = await flags(request)
            # one trip to a worker thread: the restyle and, where asked, its pixels
            r, data = await run_in_threadpool(styled, style, estimator, params, quick, wait, fmt)
        except (ValueError, StyletraceError) as exc:
            return bad(str(exc))
        if r.shown is None:
            return bad("no image yet: the first pass is still rendering", 409)
        shown = r.shown
        draft = shown.kind == "draft"
        meta = {"spp": 0 if draft else shown.spp, "draft": draft,
                "command": session.command(style, estimator, params, draft=draft),
                "quick": r.quick, "busy": r.busy, "stamp": r.stamp, "version": shown.version,
                "kind": shown.kind, "label": shown.label, "restyle_ms": r.seconds * 1e3}
        if fmt == "rgba8":  # no PNG, no base64: the page draws these bytes as they come
            if data is None:
                return Response(status_code=204, headers=restyle_headers(meta, t))
            h, w = r.image.shape[:2]
            return Response(data, media_type="application/octet-stream",
                            headers=restyle_headers({**meta, "width": w, "height": h}, t))
        png = None if r.image is None else await run_in_threadpool(encode_image_file, r.image,
                                                                   "png")
        image = None if png is None else \
            "data:image/png;base64," + base64.b64encode(png).decode("ascii")
        return JSONResponse({"image": image, **meta, "ms": (time.perf_counter() - t) * 1e3})

    async def save(request: Request):
        try:
            style, estimator, params = await parse(request)
            body = await request.json()
            fmt = body.get("format", "png")
            if fmt not in ("png", "exr"):
                raise ValueError(f"bad format {fmt!r}: expected png or exr")
            img, spp, _ = await run_in_threadpool(session.restyle, style, estimator, params)
        except (ValueError, StyletraceError) as exc:
            return bad(str(exc))
        if img is None:
            return bad("no image yet: the first pass is still rendering", 409)
        data = await run_in_threadpool(encode_image_file, img, fmt)
        media = "image/png" if fmt == "png" else "image/x-exr"
        return Response(
            data,
            media_type=media,
            headers={
                "Content-Disposition": f'attachment; filename="{style}-{spp}spp.{fmt}"',
                "X-Spp": str(spp),
            },
        )

    return Starlette(
        routes=[
            Route("/", page),
            Route("/api/styles", styles),
            Route("/api/state", state),
            Route("/api/restyle", do_restyle, methods=["POST"]),
            Route("/api/save", save, methods=["POST"]),
        ]
    )


def serve(job, port: int = 8765) -> int:
    """Run the preview server on 127.0.0.1 until Ctrl-C; prints the page's URL once it listens.

    Args:
        job: the page's render (`preview.jobs.page_job`): its scene, counts, size, seed,
            denoising, and the style the page starts with.
        port: the port (0: a free one).

    Returns:
        The exit status, 0.

    Raises:
        StyletraceError: a bad style or parameter, a per-sample style, a refusal of the session
            (one line, before the server listens).
    """
    import uvicorn

    from styletrace.config.settings import parse_slot
    from styletrace.preview.session import Session
    # a bad start fails here, in one line
    given = {k: v for k, v in job.given.items() if k != "inner_samples"}
    slot = parse_slot(given, context="preview")
    if slot.style.per_sample:
        raise UsageError(
            f"style '{slot.style.name}' cannot be previewed: it applies g to every child sample, "
            f"and the preview's buffer keeps only their mean"
        )
    session = Session(job).start()
    app = make_app(session)
    config = uvicorn.Config(app, host="127.0.0.1", port=port, log_level="warning")
    server = uvicorn.Server(config)

    import threading

    def announce():
        while not server.started:
            time.sleep(0.02)
        sock = server.servers[0].sockets[0]
        print(f"styletrace preview: http://127.0.0.1:{sock.getsockname()[1]}/", flush=True)
    threading.Thread(target=announce, daemon=True).start()
    try:
        server.run()
    finally:
        session.stop()
    print("styletrace preview: stopped", file=sys.stderr)
    return 0


__all__ = ["make_app", "serve", "styles_table", "encode_image_file", "rgba8", "FORMATS"]
