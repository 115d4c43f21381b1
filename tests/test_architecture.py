"""The package's folders are its layers, and docs/architecture.md stays true.

Read from the code, not from a table: every import of a styletrace module, at load time or inside a
function, is an arrow from the importer's folder to the imported module's folder. The folders must
form no cycle, and no function-local import may point up (to a folder that reaches the importer's
own folder through load-time imports). The package's entry files (`styletrace/__init__.py`,
`styletrace/__main__.py`) are its facade and may load anything on first use.
"""
import ast
import os
import re
import shutil

from conftest import SRC

PACKAGE = os.path.join(SRC, "styletrace")
MAP = os.path.join(os.path.dirname(SRC), "docs", "architecture.md")
FACADE = ("__init__.py", "__main__.py")


def module_files(package: str) -> dict[str, str]:
    """Dotted module name -> file, for every module under `package` (a package is its __init__)."""
    out = {}
    top = os.path.dirname(package)
    for folder, _, files in os.walk(package):
        for f in files:
            if f.endswith(".py"):
                path = os.path.join(folder, f)
                name = os.path.relpath(path, top)[:-3].replace(os.sep, ".")
                out[name[: -len(".__init__")] if name.endswith(".__init__") else name] = path
    return out


def folder_of(path: str, package: str) -> str:
    """The folder holding a module file, relative to the package ('' for its root, 'kernel')."""
    rel = os.path.relpath(os.path.dirname(path), package).replace(os.sep, "/")
    return "" if rel == "." else rel


class Imports(ast.NodeVisitor):
    """Every import in one module's tree, with whether it sits inside a function."""

    def __init__(self):
        self.found: list[tuple[ast.AST, bool]] = []
        self.depth = 0

    def visit_FunctionDef(self, node):
        self.depth += 1
        self.generic_visit(node)
        self.depth -= 1

    visit_AsyncFunctionDef = visit_FunctionDef

    def visit_Import(self, node):
        self.found.append((node, self.depth > 0))

    visit_ImportFrom = visit_Import


def arrows(package: str) -> list[tuple[str, str, bool, str]]:
    """(importer folder, imported folder, function-local, 'module:line -> module') for each
    import of a module in another folder of `package`; the facade's imports are left out."""
    files = module_files(package)
    out = []
    for name, path in files.items():
        if os.path.relpath(path, package) in FACADE:
            continue
        base = name if path.endswith("__init__.py") else name.rpartition(".")[0]
        visitor = Imports()
        with open(path) as fh:
            visitor.visit(ast.parse(fh.read()))
        for node, local in visitor.found:
            if isinstance(node, ast.Import):
                targets = [a.name for a in node.names]
            else:
                if node.level:
                    parts = base.split(".")
                    mod = ".".join(parts[: len(parts) - node.level + 1] + [node.module or ""])
                else:
                    mod = node.module or ""
                mod = mod.rstrip(".")
                targets = [f"{mod}.{a.name}" if f"{mod}.{a.name}" in files else mod
                           for a in node.names]
            for target in targets:
                if target in files and target != name:
                    here = folder_of(path, package)
                    there = folder_of(files[target], package)
                    if here != there:
                        out.append((here, there, local, f"{name}:{node.lineno} -> {target}"))
    return out


def folder_cycle(edges: list[tuple[str, str, bool, str]]) -> list[str]:
    """One cycle of the folder graph, as the imports that close it; [] if there is none."""
    graph: dict[str, dict[str, str]] = {}
    for a, b, local, why in edges:
        graph.setdefault(a, {}).setdefault(b, why + (" (inside a function)" if local else ""))
    state: dict[str, int] = {}
    stack: list[str] = []

    def visit(node):
        state[node] = 1
        stack.append(node)
        for nxt in sorted(graph.get(node, {})):
            if state.get(nxt) == 1:
                ring = stack[stack.index(nxt):] + [nxt]
                return [graph[x][y] for x, y in zip(ring, ring[1:])]
            if nxt not in state:
                found = visit(nxt)
                if found:
                    return found
        stack.pop()
        state[node] = 2
        return []

    for start in sorted(graph):
        if start not in state:
            found = visit(start)
            if found:
                return found
    return []


def reaches(edges, start: str, goal: str) -> bool:
    """Whether folder `start` reaches `goal` through load-time imports."""
    graph: dict[str, set[str]] = {}
    for a, b, local, _ in edges:
        if not local:
            graph.setdefault(a, set()).add(b)
    seen, todo = set(), [start]
    while todo:
        node = todo.pop()
        if node == goal:
            return True
        if node not in seen:
            seen.add(node)
            todo.extend(graph.get(node, ()))
    return False


def upward_local_imports(edges) -> list[str]:
    """Function-local imports of a folder that reaches the importer's folder at load time."""
    return [why for a, b, local, why in edges if local and reaches(edges, b, a)]


def folder_layers(edges, package: str = PACKAGE) -> dict[str, int]:
    """Each folder's layer: 0 for one that imports no other folder, else one above the highest it
    imports. Needs an acyclic graph."""
    graph: dict[str, set[str]] = {
        folder_of(p, package): set() for p in module_files(package).values()
    }
    for a, b, _, _ in edges:
        graph.setdefault(a, set()).add(b)
        graph.setdefault(b, set())
    memo: dict[str, int] = {}

    def layer(node):
        if node not in memo:
            memo[node] = 1 + max((layer(n) for n in graph[node]), default=-1)
        return memo[node]

    return {f: layer(f) for f in graph}


def test_no_two_folders_import_each_other():
    cycle = folder_cycle(arrows(PACKAGE))
    assert not cycle, "the folders form a cycle: " + "; ".join(cycle)


def test_no_function_local_import_points_up():
    up = upward_local_imports(arrows(PACKAGE))
    assert not up, "function-local imports pointing up: " + "; ".join(up)


def test_the_checks_catch_a_planted_cycle_and_a_planted_local_upward_import(tmp_path):
    """Not vacuous: a copy of the package with one upward import planted fails each check."""
    edges = arrows(PACKAGE)
    layers = folder_layers(edges)
    low = min(layers, key=lambda f: (layers[f], f))
    high = max(layers, key=lambda f: (layers[f], f))
    assert reaches(edges, high, low), (low, high)
    target = next(m for m, p in module_files(PACKAGE).items()
                  if folder_of(p, PACKAGE) == high and not p.endswith("__init__.py"))
    victim = next(p for p in module_files(PACKAGE).values()
                  if folder_of(p, PACKAGE) == low and os.path.relpath(p, PACKAGE) not in FACADE)
    for local, check in ((False, folder_cycle), (True, upward_local_imports)):
        copy = tmp_path / ("local" if local else "top") / "styletrace"
        shutil.copytree(PACKAGE, copy, ignore=shutil.ignore_patterns("__pycache__"))
        planted = copy / os.path.relpath(victim, PACKAGE)
        line = f"import {target}\n"
        if local:
            line = f"\n\ndef _planted():\n    {line}"
        planted.write_text(planted.read_text() + line)
        assert not check(arrows(PACKAGE)), "the real package must pass before planting"
        assert check(arrows(str(copy))), f"a planted {'local' if local else 'top-level'} import " \
                                         f"from {low or 'the root'} to {high} went unseen"


def modules() -> list[str]:
    """Every module file under src/styletrace, relative to it, package __init__s apart."""
    return sorted(os.path.relpath(p, PACKAGE).replace(os.sep, "/")
                  for p in module_files(PACKAGE).values()
                  if not p.endswith("__init__.py") or os.path.dirname(p) == PACKAGE)


def text() -> str:
    with open(MAP) as f:
        return f.read()


def named(doc: str) -> set[str]:
    """The module paths the code map (the first fenced block) names, relative to src/styletrace."""
    return set(re.findall(r"(?<![\w/.])((?:\w+/)*\w+\.py)\b", doc.split("```")[1]))


def test_every_module_is_on_the_map():
    missing = [m for m in modules() if m not in named(text())]
    assert not missing, f"docs/architecture.md does not name: {', '.join(missing)}"


def test_every_file_the_map_names_exists():
    have = set(modules())
    gone = sorted(n for n in named(text()) if n not in have)
    assert not gone, f"docs/architecture.md names files that do not exist: {', '.join(gone)}"


def test_the_map_draws_every_folder_in_its_layer():
    """The folder graph in docs/architecture.md ('layer N: folder/ folder/') matches the code's."""
    drawn = {}
    for n, names in re.findall(r"^layer (\d+): (.*)$", text(), flags=re.M):
        for folder in re.findall(r"`([^`]*)/`", names):
            drawn[folder] = int(n)
    layers = folder_layers(arrows(PACKAGE))
    want = {("" if f == "" else f): n for f, n in layers.items()}
    assert drawn == want, f"docs/architecture.md draws {drawn}; the code has {want}"
