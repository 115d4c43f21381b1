"""The package's seams: side-effect-free imports, no import cycles, one way in to the engine."""
import ast
import os
import subprocess
import sys

from conftest import SRC, child_env

PACKAGE = os.path.join(SRC, "styletrace")


def run_child(code):
    return subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, env=child_env(), timeout=300
    )


def test_import_styletrace_loads_neither_drjit_nor_mitsuba():
    r = run_child(
        "import sys, styletrace, styletrace.estimators, styletrace.errors, "
        "styletrace.frontends.cli; "
        "print(sorted(m for m in ('drjit', 'mitsuba') if m in sys.modules))"
    )
    assert r.returncode == 0, r.stderr
    assert r.stdout.strip() == "[]"


def test_first_use_of_the_api_initialises_the_backend():
    r = run_child(
        "import styletrace, mitsuba as mi; f = styletrace.render; print(callable(f), mi.variant(), "
        "styletrace.variant == mi.variant()); mi.load_dict({'type': 'stylized', 'style': 'cel'})"
    )
    assert r.returncode == 0, r.stderr
    words = r.stdout.split()
    assert words[0] == "True" and words[1].endswith("_rgb") and words[2] == "True"


def test_scene_dict_is_served_after_a_bare_import():
    """docs/guide.md builds a per-object scene from `styletrace.scene_dict` after `import
    styletrace` alone (it once named `styletrace.frontends.api`, which that import does not
    load)."""
    r = run_child(
        "import styletrace; d = styletrace.scene_dict('dragon', 8, 8); "
        "print(d['type'], 'dragon' in d, 'scene_dict' in styletrace.__all__)"
    )
    assert r.returncode == 0, r.stderr
    assert r.stdout.split() == ["scene", "True", "True"]


def test_the_plugin_modules_import_on_their_own():
    """`styletrace.render` was both a function and a subpackage; the plugins now live in
    `styletrace.kernel`."""
    r = run_child(
        "import styletrace.kernel.integrator as m, styletrace; print(m.StylizedIntegrator.__name__)"
    )
    assert r.returncode == 0, r.stderr
    assert r.stdout.strip() == "StylizedIntegrator"


def test_init_is_idempotent_and_keeps_the_variant():
    import mitsuba as mi

    import styletrace
    first = styletrace.init()
    assert styletrace.init() == first == mi.variant()
    assert styletrace.init(first) == first
    mi.load_dict({"type": "stylized"})  # registered


def module_name(path):
    rel = os.path.relpath(path, SRC)[:-3].replace(os.sep, ".")
    return rel[: -len(".__init__")] if rel.endswith(".__init__") else rel


def import_graph():
    """Module -> the styletrace modules it imports, at load time or inside functions."""
    modules = {}
    for folder, _, files in os.walk(PACKAGE):
        for f in files:
            if f.endswith(".py"):
                path = os.path.join(folder, f)
                modules[module_name(path)] = path
    graph = {}
    for name, path in modules.items():
        is_pkg = path.endswith("__init__.py")
        base = name if is_pkg else name.rpartition(".")[0]
        deps = set()
        for node in ast.walk(ast.parse(open(path).read())):
            if isinstance(node, ast.Import):
                deps.update(a.name for a in node.names)
            elif isinstance(node, ast.ImportFrom):
                if node.level:
                    parts = base.split(".")
                    parts = parts[: len(parts) - node.level + 1]
                    target = ".".join(parts + ([node.module] if node.module else []))
                else:
                    target = node.module or ""
                for alias in node.names:
                    sub = f"{target}.{alias.name}"
                    deps.add(sub if sub in modules else target)
        graph[name] = {d for d in deps if d in modules and d != name}
    return graph


def cycles(graph):
    """Strongly connected components with more than one module (Tarjan)."""
    index, low, stack, on, out = {}, {}, [], set(), []

    def visit(v):
        index[v] = low[v] = len(index)
        stack.append(v)
        on.add(v)
        for w in graph[v]:
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            comp = []
            while True:
                w = stack.pop()
                on.discard(w)
                comp.append(w)
                if w == v:
                    break
            if len(comp) > 1:
                out.append(sorted(comp))

    for v in graph:
        if v not in index:
            visit(v)
    return out


def test_no_import_cycles():
    graph = import_graph()
    # a package importing its own submodules to register them is not a cycle of the code's layers
    for name in graph:
        graph[name] = {
            d for d in graph[name] if not (d.startswith(name + ".") and name in ("styletrace",))
        }
    assert cycles(graph) == []


def test_the_cycle_check_finds_a_cycle():
    assert cycles({"a": {"b"}, "b": {"c"}, "c": {"a"}, "d": {"a"}}) == [["a", "b", "c"]]


def test_only_the_engine_layers_import_drjit_or_mitsuba():
    """Dr.Jit picks its libLLVM when first imported: modules that import it at load time sit
    below a guard (`jit.backend()` in `styles`, `kernel`, `scene`, `api`), and the estimators and
    front ends import it nowhere."""
    graph_free = ("styletrace", "styletrace.errors", "styletrace.jit", "styletrace.scene.plugins",
                  "styletrace.frontends.cli", "styletrace.frontends.gallery")
    for name in graph_free:
        path = os.path.join(PACKAGE, *name.split(".")[1:]) + ".py" if name != "styletrace" else \
            os.path.join(PACKAGE, "__init__.py")
        tree = ast.parse(open(path).read())
        top = [n for n in tree.body if isinstance(n, (ast.Import, ast.ImportFrom))]
        names = {a.name for n in top if isinstance(n, ast.Import) for a in n.names} | \
                {n.module for n in top if isinstance(n, ast.ImportFrom) and n.module}
        assert not names & {"drjit", "mitsuba"}, name
