"""Reference tables for the README and docs/, generated from the registries so they cannot drift.

Markdown files hold blocks between `<!-- reference:NAME -->` and `<!-- /reference -->`; this module
rewrites each block from the code:

| block | source |
|---|---|
| `integrator` | the integrator's properties (`config.settings.PROPERTIES`) |
| `estimators` | the estimator registry (`config.estimator_registry`) |
| `style:NAME` | a style's parameters (`styles` registry) |

    python -m styletrace.frontends.reference            # rewrite README.md and docs/*.md in place
    # exit 1 if a block is stale (the tests check this too)
    python -m styletrace.frontends.reference --check
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
    from styletrace.styles import style_class
    cls = style_class(name)
    if not cls.params:
        return "No parameters.\n"
    rows = [_row("parameter", "type", "default", "meaning", "allowed"), "|---|---|---|---|---|"]
    for p in cls.params:
        rows.append(_row(p.name, p.kind, f"`{p.show(p.default)}`", p.explain(), p.allowed()))
    return "\n".join(rows) + "\n"


def block(name: str) -> str:
    if name == "integrator":
        return integrator_table()
    if name == "estimators":
        return estimator_table()
    if name.startswith("style:"):
        return style_table(name.split(":", 1)[1])
    raise KeyError(f"unknown reference block {name!r}")


def render_file(text: str) -> str:
    """`text` with every reference block regenerated."""
    return BLOCK.sub(lambda m: m.group(1) + block(m.group("name")) + m.group(4), text)


def files(root: str) -> list[str]:
    return [os.path.join(root, "README.md")] + sorted(glob.glob(os.path.join(root, "docs", "*.md")))


def reference_main(argv=None) -> int:
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
