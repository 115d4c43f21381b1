"""`styletrace preview`: tune a style live in the browser over a growing expectation buffer.

    session.py  the scene, the background render that grows the buffer, restyles under one lock
    server.py   the Starlette app (JSON API, docs/preview.md) and `serve` (uvicorn on 127.0.0.1)
    page.html   the page: image, style picker and parameter controls from the registry, save,
                command line
"""
