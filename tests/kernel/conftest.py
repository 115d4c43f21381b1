import styletrace

styletrace.init()  # the kernel tests render: pick the backend and register the plugins first

from helpers.furnace_fixtures import mask, scene  # noqa: E402,F401  (pytest finds fixtures by name here)
