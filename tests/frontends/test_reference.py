"""The reference tables in README.md and docs/ are generated from the registries and agree with
them."""
import os
import re
import sys

import pytest

import styletrace
from styletrace.config.settings import PROPERTIES
from styletrace.frontends import reference
from styletrace.styles import style_class, style_names

styletrace.init()
ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))


@pytest.mark.parametrize("path", reference.files(ROOT), ids=os.path.basename)
def test_generated_blocks_are_up_to_date(path):
    text = open(path, encoding="utf-8").read()
    assert reference.render_file(text) == text, (
        f"run: python -m styletrace.frontends.reference ({path} is stale)"
    )


def test_every_table_has_its_block():
    python_md = open(os.path.join(ROOT, "docs", "python.md"), encoding="utf-8").read()
    styles_md = open(os.path.join(ROOT, "docs", "styles.md"), encoding="utf-8").read()
    estimators_md = open(os.path.join(ROOT, "docs", "estimators.md"), encoding="utf-8").read()
    assert "<!-- reference:integrator -->" in python_md
    assert "<!-- reference:estimators -->" in estimators_md
    for name in style_names():
        if style_class(name).params:
            assert f"<!-- reference:style:{name} -->" in styles_md, name


@pytest.mark.parametrize("name", style_names())
def test_every_style_has_its_section_and_thumbnail_in_styles_md(name):
    """`styletrace styles` lists the registry; docs/styles.md shows each with a thumbnail that
    exists (docs/make_thumbnails.py makes them; `coordinate` was listed but not shown)."""
    styles_md = open(os.path.join(ROOT, "docs", "styles.md"), encoding="utf-8").read()
    assert f"\n## {name}\n" in styles_md
    assert f"![{name}](styles/{name}.png)" in styles_md
    assert os.path.isfile(os.path.join(ROOT, "docs", "styles", f"{name}.png"))


def test_the_tables_carry_every_registry_entry():
    table = reference.integrator_table()
    for p in PROPERTIES:
        assert f"`{p.name}`" in table and p.doc in table
    for name in style_names():
        for p in style_class(name).params:
            assert p.doc.replace("|", "\\|") in reference.style_table(name)


def test_a_stale_block_is_rewritten():
    stale = "intro\n<!-- reference:style:cel -->\n| old | table |\n<!-- /reference -->\nend\n"
    fresh = reference.render_file(stale)
    assert (
        "| old | table |" not in fresh
        and reference.style_table("cel") in fresh
        and fresh.endswith("end\n")
    )


@pytest.mark.parametrize("name", style_names())
def test_each_style_module_opens_with_its_parameters_and_defaults(name):
    """The third place a style's parameters appear, its module's reference block, names each with
    its default."""
    cls = style_class(name)
    doc = sys.modules[cls.__module__].__doc__
    for p in cls.params:
        assert f"- {p.name} (" in doc or f", {p.name} (" in doc, (name, p.name)
        # derived and gradient defaults are described in words
        if isinstance(p.default, (int, float, tuple)):
            m = re.search(rf"\b{p.name} \([^)]*default ([^\s,)]+(?:,[^\s,)]+)*)", doc)
            assert m and p.parse(m.group(1)) == p.default, (name, p.name, p.show(p.default))
