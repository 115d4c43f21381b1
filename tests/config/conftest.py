from helpers.furnace_fixtures import mask, scene

import styletrace

#: pytest finds fixtures by name here
__all__ = ["mask", "scene"]

# the configuration tests render (the estimator registry on the furnace): pick the backend and
# register the plugins first
styletrace.init()
