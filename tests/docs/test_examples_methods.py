"""The examples of the docs pages in GROUPS["methods"] run, and print what the docs show
(tests/docs/examples.py has the rules)."""
import pytest

from .examples import GROUPS, collect, run_case

EXAMPLES = collect(GROUPS["methods"])


@pytest.mark.parametrize("example", EXAMPLES, ids=[e.id for e in EXAMPLES])
def test_example(example, docs_pages):
    run_case(example, EXAMPLES, docs_pages)
