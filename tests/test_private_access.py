"""No module outside the integrator's own files reads or writes the `stylized` integrator's private
attributes.

Its per-render state belongs to `kernel/render_context.py` (set and released there), its methods to
`kernel/integrator.py`; the other modules (reuse, the recording integrator, the front ends, the
tests' helpers) use the public seams: `targets_for`, `styled_mask`, `estimate`, `through`,
`stylized`, `child`, `walk`, `RenderContext`. The private names are read from integrator.py itself
(its `_methods` and the `self._x` it assigns), so a new one is covered as soon as it exists.
"""
import ast
import os

from conftest import SRC

PACKAGE = os.path.join(SRC, "styletrace")
OWNERS = ("kernel/integrator.py", "kernel/render_context.py")


def parse(rel: str) -> ast.Module:
    with open(os.path.join(PACKAGE, rel)) as f:
        return ast.parse(f.read())


def private_names() -> set[str]:
    """The underscore attributes StylizedIntegrator defines: its methods and what it assigns on
    `self`."""
    tree = parse("kernel/integrator.py")
    cls = next(
        n for n in tree.body if isinstance(n, ast.ClassDef) and n.name == "StylizedIntegrator"
    )
    names = {n.name for n in cls.body if isinstance(n, ast.FunctionDef) and n.name.startswith("_")
             and not n.name.startswith("__")}
    for node in ast.walk(cls):
        if (
            isinstance(node, ast.Attribute)
            and isinstance(node.value, ast.Name)
            and node.value.id == "self"
            and isinstance(node.ctx, ast.Store)
            and node.attr.startswith("_")
            and not node.attr.startswith("__")
        ):
            names.add(node.attr)
    return names


def accesses(tree: ast.AST, names: set[str]) -> list[tuple[int, str]]:
    return [
        (n.lineno, n.attr)
        for n in ast.walk(tree)
        if isinstance(n, ast.Attribute) and n.attr in names
    ]


def test_the_private_names_are_found():
    names = private_names()
    assert {"_sample", "_radiance", "_walk", "_lane_moments", "_stats"} <= names, names
    # and a use of one is seen: the check is not vacuous
    assert accesses(ast.parse("def f(integ):\n    return integ._walk(1)\n"), names) == [
        (2, "_walk")
    ]


def test_no_module_outside_the_integrator_touches_its_private_attributes():
    names = private_names()
    found = []
    for folder, _, files in os.walk(PACKAGE):
        for f in files:
            rel = os.path.relpath(os.path.join(folder, f), PACKAGE).replace(os.sep, "/")
            if f.endswith(".py") and rel not in OWNERS:
                found += [f"{rel}:{line} .{attr}" for line, attr in accesses(parse(rel), names)]
    assert not found, (
        "private attributes of StylizedIntegrator used outside its files: " + ", ".join(found)
    )
