"""Reference tables for the README and docs/, generated from the registries so they cannot drift.

Markdown files hold blocks between `<!-- reference:NAME -->` and `<!-- /reference -->`, rewritten
from the code: `integrator` (the integrator's properties, `config.settings.PROPERTIES`),
`estimators` (the estimator registry, `config.estimator_registry`) and `style:NAME` (a style's
parameters, the `styles` registry).

    python -m styletrace.frontends.reference            # rewrite README.md and docs/*.md in place
    python -m styletrace.frontends.reference --check    # exit 1 if a block is stale (tested too)
"""
from __future__ import annotations

import glob
import os
import re
import sys

BLOCK = re.compile(
    r"(<!-- reference:(?P<name>[\w:]+) -->\n)(?P<body>.*?)(<!-- /reference -->)", re.S
)


def _row(*cells) -> str:
    return "| " + " | ".join(str(c).replace("|", "\\|") for c in cells) + " |"


def integrator_table() -> str:
    from styletrace.config.settings import PROPERTIES
    rows = [_row("property", "type", "default", "flag", "meaning"), "|---|---|---|---|---|"]
    for p in PROPERTIES:
        default = (
            ("the style's" if p.name == "inner_samples" else "auto")
            if p.default is None
            else f"`{p.default}`"
        )
        rows.append(_row(f"`{p.name}`", p.kind, default, f"`{p.flag}`" if p.flag else "", p.doc))
        if p.name == "style":
            rows.append(_row("*style parameters*", "", "the style's", "`--set KEY=VALUE`",
                             "under their registry names (`styletrace styles`, docs/styles.md)"))
    return "\n".join(rows) + "\n"


def estimator_table() -> str:
    from styletrace.config.estimator_registry import kinds
    from styletrace.styles import style_class, style_names
    styles = [style_class(n)() for n in style_names()]
    rows = [
        _row("estimator", "forms of g", "styles", "inner_samples n means", "what it is"),
        "|---|---|---|---|---|",
    ]
    for k in kinds():
        extra = "; ".join(f"{key} {value}" for key, value in k.params.items())
        fits = [s.name for s in styles if k.accepts(s)]
        rows.append(
            _row(
                f"`{k.name}`",
                k.describe_forms(),
                "all" if len(fits) == len(styles) else ", ".join(fits),
                k.inner,
                k.doc + (f" ({extra})" if extra else ""),
            )
        )
    return "\n".join(rows) + "\n"


def style_table(name: str) -> str:
    """The parameter table of one style.

    Args:
        name: the style's registry name.

    Returns:
        A Markdown table (parameter, type, default, meaning, allowed), or "No parameters.".
    """
    from styletrace.styles import style_class
    cls = style_class(name)
    if not cls.params:
        return "No parameters.\n"
    rows = [_row("parameter", "type", "default", "meaning", "allowed"), "|---|---|---|---|---|"]
    for p in cls.params:
        rows.append(_row(p.name, p.kind, f"`{p.show(p.default)}`", p.explain(), p.allowed()))
    return "\n".join(rows) + "\n"


def block(name: str) -> str:
    """The generated body of a reference block.

    Args:
        name: "integrator", "estimators" or "style:NAME".

    Returns:
        Its Markdown table.

    Raises:
        KeyError: an unknown block name.
    """
    if name == "integrator":
        return integrator_table()
    if name == "estimators":
        return estimator_table()
    if name.startswith("style:"):
        return style_table(name.split(":", 1)[1])
    raise KeyError(f"unknown reference block {name!r}")


def render_file(text: str) -> str:
    """`text` with every reference block regenerated.

    Args:
        text: a Markdown file's text.

    Returns:
        The new text.

    Raises:
        KeyError: a block of an unknown name.
    """
    return BLOCK.sub(lambda m: m.group(1) + block(m.group("name")) + m.group(4), text)


def files(root: str) -> list[str]:
    """The files whose blocks are kept: README.md and docs/*.md.

    Args:
        root: the checkout's root.

    Returns:
        Their paths.
    """
    return [os.path.join(root, "README.md")] + sorted(glob.glob(os.path.join(root, "docs", "*.md")))


def reference_main(argv=None) -> int:
    """Rewrite the stale blocks in place, or with --check only name them (on stderr).

    Args:
        argv: the arguments (None: sys.argv[1:]): --check, and the checkout's root (default: the
            current folder).

    Returns:
        The exit status: 1 with --check where a block is stale, else 0.
    """
    from styletrace.scene.plugins import init
    init()
    args = sys.argv[1:] if argv is None else argv
    check = "--check" in args
    root = next((a for a in args if not a.startswith("--")), os.getcwd())
    stale = []
    for path in files(root):
        text = open(path, encoding="utf-8").read()
        new = render_file(text)
        if new != text:
            stale.append(path)
            if not check:
                tmp = path + ".tmp"
                with open(tmp, "w", encoding="utf-8") as f:
                    f.write(new)
                os.replace(tmp, path)
    for path in stale:
        print(f"{'stale' if check else 'updated'}: {path}", file=sys.stderr)
    return 1 if check and stale else 0


if __name__ == "__main__":
    sys.exit(reference_main())
