"""Local setup for the estimator tests.

The estimators run on numpy without Dr.Jit or Mitsuba; the Dr.Jit tests get their array types from
the ``jit`` fixture: the Dr.Jit module of the backend in use (``drjit.llvm`` or ``drjit.cuda``, or
their ``.ad`` submodules once a Mitsuba variant is active), obtained after
``styletrace.jit.prepare_drjit()`` pointed Dr.Jit at a working libLLVM. So the suite runs unchanged
on a CPU-only or a CUDA-only machine. (tests/conftest.py puts the source tree on sys.path;
``estimator_stats`` is imported relatively.)
"""
import pytest

from .estimator_stats import drjit_backend


@pytest.fixture
def jit():
    """The Dr.Jit array module to build test arrays with (Float, Array3f, Bool, UInt32, ...)."""
    return drjit_backend()
