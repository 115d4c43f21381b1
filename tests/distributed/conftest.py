import os

import pytest
from conftest import SRC

import styletrace

styletrace.init()


@pytest.fixture(scope="session")
def ray_cluster():
    """A real local Ray instance of 2 CPUs for the tests of this folder; its workers import our
    src/."""
    ray = pytest.importorskip("ray")
    os.environ["PYTHONPATH"] = os.pathsep.join(p for p in (SRC, os.environ.get("PYTHONPATH")) if p)
    if not ray.is_initialized():
        ray.init(num_cpus=2, include_dashboard=False, logging_level="warning", log_to_driver=False)
    yield ray.get_runtime_context().gcs_address
    ray.shutdown()
