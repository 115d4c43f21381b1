from helpers.furnace_fixtures import mask, scene

import styletrace

#: pytest finds fixtures by name here
__all__ = ["mask", "scene"]

styletrace.init()  # the kernel tests render: pick the backend and register the plugins first
