"""docs/architecture.md is true and stays true: every module is on the map, every file named exists, and no
import points upwards in the map's layer table (imports as tests/test_imports.py reads them, function-level
imports included)."""
import os
import re

from conftest import SRC
from test_imports import import_graph

PACKAGE = os.path.join(SRC, "styletrace")
MAP = os.path.join(os.path.dirname(SRC), "docs", "architecture.md")


def modules() -> list[str]:
    """Every module file under src/styletrace, relative to it ('kernel/reuse/pool.py'), package __init__s apart."""
    out = []
    for folder, _, files in os.walk(PACKAGE):
        for f in files:
            rel = os.path.relpath(os.path.join(folder, f), PACKAGE).replace(os.sep, "/")
            if f.endswith(".py") and (f != "__init__.py" or rel == "__init__.py"):
                out.append(rel)
    return sorted(out)


def text() -> str:
    with open(MAP) as f:
        return f.read()


def named(doc: str) -> set[str]:
    """The module paths the code map (the first fenced block) names, relative to src/styletrace."""
    return set(re.findall(r"(?<![\w/.])((?:\w+/)*\w+\.py)\b", doc.split("```")[1]))


def layer_table(doc: str) -> list[tuple[int, list[str]]]:
    rows = re.findall(r"^\| (\d+) [^|]*\| (.*) \|$", doc, flags=re.M)
    return [(int(n), re.findall(r"`([^`]+)`", cells)) for n, cells in rows]


def layer_of(rel: str, table) -> int | None:
    """The layer of module path `rel`: the entry naming the file, else the deepest folder entry holding it."""
    best, depth = None, -1
    for n, entries in table:
        for e in entries:
            if e == rel:
                return n
            if e.endswith("/") and rel.startswith(e) and len(e) > depth:
                best, depth = n, len(e)
    return best


def test_every_module_is_on_the_map():
    missing = [m for m in modules() if m not in named(text())]
    assert not missing, f"docs/architecture.md does not name: {', '.join(missing)}"


def test_every_file_the_map_names_exists():
    have = set(modules())
    gone = sorted(n for n in named(text()) if n not in have)
    assert not gone, f"docs/architecture.md names files that do not exist: {', '.join(gone)}"


def test_every_module_has_a_layer():
    table = layer_table(text())
    assert len(table) >= 5
    missing = [m for m in modules() if layer_of(m, table) is None]
    assert not missing, f"no layer in docs/architecture.md for: {', '.join(missing)}"


def path_of(module: str) -> str:
    """'styletrace.kernel.reuse' -> 'kernel/reuse/pool.py'; a package -> its folder's __init__.py."""
    rel = module.split(".", 1)[1].replace(".", "/") if "." in module else ""
    if os.path.isdir(os.path.join(PACKAGE, rel)):
        return (rel + "/__init__.py") if rel else "__init__.py"
    return rel + ".py"


def test_no_import_points_upwards():
    table = layer_table(text())
    upward = []
    for module, deps in import_graph().items():
        here = layer_of(path_of(module), table)
        for dep in deps:
            there = layer_of(path_of(dep), table)
            if here is not None and there is not None and there > here:
                upward.append(f"{module} (layer {here}) imports {dep} (layer {there})")
    assert not upward, "; ".join(sorted(upward))


def test_the_checks_see_a_module_left_off_and_an_upward_import():
    """The checks above are not vacuous: a map without one module's name, and a plugin placed under the
    pipeline, are caught."""
    doc = text()
    assert "kernel/reuse/pool.py" in named(doc)
    assert "kernel/reuse/pool.py" not in named(doc.replace("kernel/reuse/pool.py", "kernel/reuse/xxxxx.py"))
    table = layer_table(doc)
    assert layer_of("kernel/reuse/pool.py", table) < layer_of("pipeline/passes.py", table)
    assert layer_of("distributed/run.py", table) < layer_of("distributed/command.py", table)
