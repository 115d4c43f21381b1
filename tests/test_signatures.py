"""Objects, not waterfalls (issue 44): no function outside the kernel takes more than 7 parameters
without a reason written in its docstring.

`self` and `cls` do not count; *args and **kwargs count one each. The reason is written with the
words "more than 7 parameters" in the function's docstring, or for an `__init__` in its class's
(where the constructor's arguments are documented). Parameters that travel together are a value
object instead (`pipeline.passes.Shot`, `PassSplit`, `pipeline.denoising.Denoising`, ...).
"""
import ast
from pathlib import Path

#: the most parameters a function takes without a written reason
MOST = 7
#: the words that mark the reason
REASON = "more than 7 parameters"
SOURCE = Path(__file__).resolve().parents[1] / "src" / "styletrace"
#: the kernel's functions follow Mitsuba's own signatures (sample, eval, ...): not scanned
KERNEL = SOURCE / "kernel"


def count(args: ast.arguments) -> int:
    """The parameters that count: all named ones but a leading self or cls, *args, **kwargs."""
    named = [*args.posonlyargs, *args.args, *args.kwonlyargs]
    n = len(named) + (args.vararg is not None) + (args.kwarg is not None)
    if named and named[0].arg in ("self", "cls"):
        n -= 1
    return n


def offenders(root: Path = SOURCE, skip: Path = KERNEL) -> list[str]:
    """Every function of `root` (`skip`, the kernel, excluded) with more than MOST parameters and
    no reason, as 'path:line name (count)'."""
    out = []
    for path in sorted(root.rglob("*.py")):
        if skip in path.parents:
            continue
        tree = ast.parse(path.read_text(), str(path))
        # an __init__'s arguments are documented in its class's docstring
        class_doc = {id(item): ast.get_docstring(node) or ""
                     for node in ast.walk(tree) if isinstance(node, ast.ClassDef)
                     for item in node.body}
        for node in ast.walk(tree):
            if not isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
                continue
            n = count(node.args)
            doc = ast.get_docstring(node) or ""
            if node.name == "__init__":
                doc += class_doc.get(id(node), "")
            if n > MOST and REASON not in doc:
                out.append(f"{path.relative_to(root.parent)}:{node.lineno} {node.name} ({n})")
    return out


def test_no_function_takes_more_than_seven_parameters_without_a_reason():
    found = offenders()
    print("\n".join(found))
    assert not found, (
        f"{len(found)} function(s) with more than {MOST} parameters and no reason in the "
        f"docstring ('{REASON}'): group what travels together into a value object, or write why "
        "each is its own:\n" + "\n".join(found)
    )


def test_the_scan_counts_as_the_rule_says(tmp_path):
    """self/cls are not counted, *args and **kwargs one each; the reason may sit in an __init__'s
    class; the kernel is not scanned."""
    (tmp_path / "kernel").mkdir()
    (tmp_path / "kernel" / "k.py").write_text("def k(a, b, c, d, e, f, g, h): pass\n")
    (tmp_path / "m.py").write_text(
        "def seven(self, a, b, c, d, e, f, g): pass\n"
        "def eight(a, b, c, d, e, f, *g, **h): pass\n"
        "def why(a, b, c, d, e, f, g, h):\n"
        "    '''Takes more than 7 parameters: each is a setting.'''\n"
        "class C:\n"
        "    '''Takes more than 7 parameters: a declaration.'''\n"
        "    def __init__(self, a, b, c, d, e, f, g, h): pass\n"
        "class D:\n"
        "    def __init__(self, a, b, c, d, e, f, g, h): pass\n"
    )
    found = offenders(tmp_path, tmp_path / "kernel")
    assert [f.split(" ", 1)[1] for f in found] == ["eight (8)", "__init__ (8)"]
