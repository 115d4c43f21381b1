import pytest

from .examples import Pages


@pytest.fixture(scope="session")
def docs_pages(tmp_path_factory):
    """One folder per docs page, in which its examples run in order (tests/docs/examples.py)."""
    return Pages(tmp_path_factory.mktemp("docs"))
