import os
import sys

# Tests run against the source tree. The suites that render call styletrace.init() in their conftest
# (it picks libLLVM and the variant, and registers the plugins); the estimator tests need neither.
SRC = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", "src"))
sys.path.insert(0, SRC)
sys.path.insert(0, os.path.dirname(__file__))

# The suite tests the paper's estimators and each front end's plumbing, so its renders take
# denoise=off unless a test asks for a method: every front end's default (auto, docs/look.md) reads
# $STYLETRACE_DENOISE, which the tests of that default (tests/test_entry_points.py,
# tests/denoise/test_default.py) clear.
os.environ["STYLETRACE_DENOISE"] = "off"


def child_env(**extra):
    """The environment for a test's subprocess: our source tree put first on PYTHONPATH, what was
    there kept (a GPU machine carries its packages on it)."""
    env = dict(os.environ, **extra)
    env["PYTHONPATH"] = os.pathsep.join(p for p in (SRC, os.environ.get("PYTHONPATH")) if p)
    return env
