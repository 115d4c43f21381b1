import styletrace

styletrace.init()  # the configuration tests render (the estimator registry on the furnace): pick the backend and register the plugins first

from helpers.furnace_fixtures import mask, scene  # noqa: E402,F401  (pytest finds fixtures by name here)
