import pytest
import styletrace

styletrace.init()  # the configuration tests render (the estimator registry on the furnace): pick the backend and register the plugins first

from helpers import furnace  # noqa: E402


@pytest.fixture(scope="module")
def scene(request):
    """The furnace scene at the test module's RES."""
    return furnace.scene(request.module.RES)


@pytest.fixture(scope="module")
def mask(request):
    """Pixels inside the furnace sphere's silhouette at the test module's RES."""
    return furnace.sphere_mask(request.module.RES)
