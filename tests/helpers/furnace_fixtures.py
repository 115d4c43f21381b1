"""The furnace fixtures shared by the configuration and kernel test folders (their conftests
import them): each test module sets RES, the image side."""
import pytest

from helpers import furnace


@pytest.fixture(scope="module")
def scene(request):
    """The furnace scene at the test module's RES."""
    return furnace.scene(request.module.RES)


@pytest.fixture(scope="module")
def mask(request):
    """Pixels inside the furnace sphere's silhouette at the test module's RES."""
    return furnace.sphere_mask(request.module.RES)
