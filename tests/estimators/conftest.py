"""Local setup for the estimator tests.

Dr.Jit must find a working libLLVM before anything imports it (LLVM 15 crashes Dr.Jit 1.5), and
``styletrace.estimators`` must be importable even while the package ``__init__`` (which selects a
Mitsuba variant and registers plugins) is unavailable: the estimators need neither.
"""
import os
import sys
import types
from pathlib import Path

os.environ.setdefault("DRJIT_LIBLLVM_PATH", "/usr/lib/x86_64-linux-gnu/libLLVM-19.so")

HERE = Path(__file__).resolve().parent
SRC = HERE.parents[1] / "src"
for p in (str(SRC), str(HERE)):
    if p not in sys.path:
        sys.path.insert(0, p)

try:
    import styletrace  # noqa: F401
except Exception:  # the package __init__ is not importable yet: expose the subpackage on its own
    for name in [m for m in sys.modules if m == "styletrace" or m.startswith("styletrace.")]:
        del sys.modules[name]
    pkg = types.ModuleType("styletrace")
    pkg.__path__ = [str(SRC / "styletrace")]
    sys.modules["styletrace"] = pkg
