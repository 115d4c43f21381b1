"""The estimator package is numpy-only until asked for Dr.Jit, and its modules import each other
without cycles."""
import ast
import os
import subprocess
import sys
import textwrap

from conftest import child_env

PKG = os.path.join(
    os.path.dirname(os.path.abspath(__file__)), "..", "..", "src", "styletrace", "estimators"
)

NUMPY_ONLY = textwrap.dedent("""
    import sys
    import numpy as np
    import styletrace.estimators as E
    {extra}
    r = E.estimate_numpy(E.Mean(4), E.Uniform(0.0, 1.0), 1000, np.random.default_rng(0))
    assert r.values.shape == (1000,) and np.all(r.draws == 4), r
    r = E.estimate_numpy(E.Direct(lambda x: x * x, 2) + E.Mean(1), E.Uniform(0.0, 1.0), 1000,
                         np.random.default_rng(1), channels=3)
    assert r.values.shape == (1000, 3)
    loaded = sorted(m for m in ("drjit", "mitsuba") if m in sys.modules)
    assert not loaded, "loaded: " + ", ".join(loaded)
    print("ok")
""")


def run_child(extra=""):
    return subprocess.run([sys.executable, "-c", NUMPY_ONLY.format(extra=extra)], env=child_env(),
                          capture_output=True, text=True, timeout=120)


def test_numpy_estimates_load_neither_drjit_nor_mitsuba():
    r = run_child()
    assert r.returncode == 0 and r.stdout.strip() == "ok", r.stdout + r.stderr


def test_the_import_check_catches_a_module_that_loads_drjit():
    # the same child, with a stand-in `drjit` module put in sys.modules as an import would, must
    # fail
    r = run_child("import types; dr = sys.modules['drjit'] = types.ModuleType('drjit'); "
                  "dr.ArrayBase = type('ArrayBase', (), {})")
    assert r.returncode != 0 and "loaded: drjit" in r.stderr, r.stdout + r.stderr


def intra_package_imports():
    """module -> the estimator modules it imports (module level or inside functions)."""
    mods = {f[:-3] for f in os.listdir(PKG) if f.endswith(".py")}
    edges = {}
    for m in mods:
        with open(os.path.join(PKG, m + ".py")) as f:
            tree = ast.parse(f.read())
        deps = set()
        for node in ast.walk(tree):
            if isinstance(node, ast.ImportFrom) and node.level == 1:
                deps.update(
                    [node.module.split(".")[0]] if node.module else [a.name for a in node.names]
                )
            elif (
                isinstance(node, ast.ImportFrom)
                and node.level == 0
                and (node.module or "").startswith("styletrace.estimators")
            ):
                parts = node.module.split(".")
                deps.update([parts[2]] if len(parts) > 2 else [a.name for a in node.names])
            elif isinstance(node, ast.Import):
                deps.update(a.name.split(".")[2] for a in node.names
                            if a.name.startswith("styletrace.estimators."))
        edges[m] = {d for d in deps if d in mods and d != m}
    return edges


def test_estimator_modules_have_no_import_cycles():
    edges = intra_package_imports()
    assert "algebra" not in edges["base"] and "affine" not in edges["base"]
    edges.pop("__init__")  # the package imports every module by design; none imports the package
    assert not any("__init__" in deps for deps in edges.values())
    state = {}

    def visit(m, path):
        state[m] = "open"
        for d in sorted(edges[m]):
            assert state.get(d) != "open", "import cycle: " + " -> ".join(path + [m, d])
            if d not in state:
                visit(d, path + [m])
        state[m] = "done"

    for m in sorted(edges):
        if m not in state:
            visit(m, [])


def test_operators_still_build_sums_and_products():
    from styletrace.estimators import Mean, Product, Sum
    assert isinstance(Mean(1) + Mean(2), Sum) and isinstance(Mean(1) * Mean(2), Product)
