"""The docs examples' extractor and rewriting rules (tests/docs/examples.py), without rendering."""
import ast
import sys

from . import examples as ex

PAGE = """# A page

Some prose with `inline code` and a printed line <!-- docs-test: prints: styletrace render -->
`styletrace: auto values: cel thresholds=0.1` in it.

    styletrace render dragon --style cel --spp 64 --inner 16 -o a.png   # a comment
    styletrace.render("dragon", style="cel", spp=64)
    styletrace render scene.xml --style gamma \\
        --inner 32 -o b.png
    ... --set gamma=2.2

    styletrace render [SCENE] --style NAME --spp S

    g(u) = u^2        a formula

```python
import styletrace
buf = styletrace.render_buffer("dragon", inner=16)
buf.save("a.npz")
```

```xml
<scene version="3.0.0"/>
```

```console
$ styletrace render --style cel
styletrace: auto values: cel thresholds=0.06259
wrote out.png
```

    styletrace: a printed line no marker names

    styletrace.render(scene=None, *, style=None, **params)
"""


def test_extract_finds_each_example_with_its_line():
    found = [(e.line, e.kind) for e in ex.extract("docs/page.md", PAGE)]
    assert found == [(4, "printed"), (6, "shell"), (7, "python"), (8, "shell"), (10, "shell"),
                     (12, "shell"), (17, "python"), (27, "shell"), (32, "printed"),
                     (34, "python")]


def test_extract_reads_commands_continuations_and_output():
    es = {e.line: e for e in ex.extract("docs/page.md", PAGE)}
    assert es[6].text.startswith("styletrace render dragon") and es[6].skip is None
    assert es[8].text == "styletrace render scene.xml --style gamma --inner 32 -o b.png"
    assert es[10].text == ("styletrace render scene.xml --style gamma --inner 32 -o b.png "
                           "--set gamma=2.2")
    assert es[12].skip.startswith("a synopsis")
    assert es[17].text.splitlines()[0] == "import styletrace"
    assert es[27].text == "styletrace render --style cel"
    assert es[27].shown == [(28, "styletrace: auto values: cel thresholds=0.06259"),
                            (29, "wrote out.png")]
    assert es[34].skip.startswith("a signature")
    assert es[6].id == "page.md:6"


def test_markers_name_the_command_of_the_next_printed_line():
    es = {e.line: e for e in ex.extract("docs/page.md", PAGE)}
    assert es[4].text == "styletrace render" and es[4].exit == 0
    assert es[4].shown == [(4, "styletrace: auto values: cel thresholds=0.1")]
    assert es[32].text is None          # no marker: the test fails and asks for one
    page = ("<!-- docs-test: exit=2 prints: styletrace render x.xml -->\n\n"
            "    styletrace: error: ...\n")
    (e,) = ex.extract("docs/p.md", page)
    assert (e.kind, e.text, e.exit, e.line) == ("printed", "styletrace render x.xml", 2, 3)


def test_skips_have_reasons():
    page = ("    pip install -e .\n    bash dev.sh test\n    bash dev.sh render\n"
            "    styletrace render dragon --ray HOST:6379\n    styletrace render dragon --ray\n"
            "    X=1 blender --python a.py\n")
    skips = [(e.line, e.skip) for e in ex.extract("docs/p.md", page)]
    assert [line for line, why in skips if why] == [1, 2, 4, 6]
    assert all(why is None or len(why) > 20 for _, why in skips)


def test_every_skip_rule_is_used_and_every_page_is_in_one_group():
    grouped = [p for pages in ex.GROUPS.values() for p in pages]
    assert sorted(grouped) == sorted(ex.all_pages())
    found = ex.collect(ex.all_pages())
    reasons = {e.skip for e in found}
    unused = [rule.reason for rule in ex.SKIPS if rule.reason not in reasons]
    assert not unused, f"skip rules no example needs: {unused}"
    assert set(ex.FRAGMENT_NAMES) | set(ex.PRINTED_ELSEWHERE) <= set(ex.all_pages())


def test_small_argv_caps_counts_and_sizes_renders():
    words = "styletrace render dragon --spp 64 --inner 16:64 --samples 1024 --width 512 -o a.png"
    argv = ex.small_argv(words.split())
    assert argv[:3] == [sys.executable, "-m", "styletrace"]
    opts = dict(zip(argv[3:], argv[4:]))
    assert (opts["--spp"], opts["--inner"], opts["--width"], opts["--height"]) == (
        "4", "4:16", "16", "16")
    assert opts["--samples"] == "16"          # spp x n0: the three agree
    assert ex.small_inner("8,8") == "8,8" and ex.small_inner("2:16") == "2:16"
    assert ex.small_inner("32") == "8"
    argv = ex.small_argv("styletrace fit a.npz --target look.png".split())
    assert argv[-2:] == ["--iterations", "20"] and "look.png" in argv
    argv = ex.small_argv("styletrace preview dragon --port 8765".split(), port=1234)
    assert argv[argv.index("--port") + 1] == "1234"
    argv = ex.small_argv("styletrace gallery -o g".split())
    assert argv[-3:] == ["--size", "16", "--quick"]
    argv = ex.small_argv("bash dev.sh render".split())
    assert argv[3:5] == ["render", "lines"] and argv[argv.index("--width") + 1] == "16"
    assert ex.small_argv("python -m x -o DIR".split()) == [sys.executable, "-m", "x", "-o", "dir"]


def test_commands_equal_once_made_small_are_one_command():
    def key(text):
        return ex._argv_key(ex.small_argv(text.split(), port=0))
    assert key("styletrace gallery -o g") == key("styletrace gallery --quick -o g")
    assert key("styletrace render --spp 64 -o a.png") == key("styletrace render -o a.png --spp 8")
    assert key("styletrace render -o a.png") != key("styletrace render -o b.png")


def test_small_python_caps_keywords_and_defines_placeholders():
    program, files = ex.small_python("docs/p.md", (
        'img = styletrace.render("dragon", spp=64, inner="4:64")\n'
        'buf = styletrace.render_buffer(scene, samples=256, width=512)\n'
        'integrator = {"type": "stylized", "inner_samples": 32}\n'
        'res = styletrace.fit(buf, target=img_or_path)\n'))
    calls = {n.func.attr: {k.arg: k.value.value for k in n.keywords
                           if isinstance(k.value, ast.Constant)}
             for n in ast.walk(ast.parse(program)) if isinstance(n, ast.Call)
             and isinstance(n.func, ast.Attribute) and n.func.attr in ("render", "render_buffer")}
    assert calls["render"] == {"width": 16, "height": 16, "spp": 4, "inner": "4:16"}
    assert calls["render_buffer"] == {"samples": 16, "width": 16}    # an mi.Scene, as given
    assert "'inner_samples': 8" in program
    assert program.startswith("import styletrace\n")
    assert "scene = mi.load_file('scene.xml')" in program and "img_or_path = 'look.png'" in program
    assert sorted(files) == ["look.png", "scene.xml"]
    program, _ = ex.small_python("docs/p.md", "styletrace.render({'sensor': {}}, spp=8)\n")
    last = program.strip().splitlines()[-1]
    assert last == f"styletrace.render({ex.SMALL_SCENE}({{'sensor': {{}}}}), spp=4)"


def test_fragments_keep_the_statements_that_need_nothing_from_outside():
    program, _ = ex.small_python("docs/estimators.md", (
        "from styletrace.estimators import Pilot\nb = Pilot(1)\n"
        "value = b.run(draw, sampler)\n"))
    assert "Pilot(1)" in program and "draw" not in program


def test_placeholders_resolve_to_files(tmp_path):
    ex.provide(tmp_path, "styletrace fit a.npz --target look.png scene.xml -o DIR")
    assert (tmp_path / "scene.xml").read_text() == ex.SCENE_XML
    png = (tmp_path / "look.png").read_bytes()
    assert png[:8] == b"\x89PNG\r\n\x1a\n" and png[16:24] == bytes([0, 0, 0, 16, 0, 0, 0, 16])
    assert (tmp_path / "dir").is_dir()
    (tmp_path / "scene.xml").write_text("made earlier")
    ex.provide(tmp_path, "styletrace render scene.xml")
    assert (tmp_path / "scene.xml").read_text() == "made earlier"


def test_printed_lines_compare_by_shape():
    assert ex.shape("styletrace: auto values: cel thresholds=0.06259,1e-3  (3 s)") == (
        "styletrace: auto values: cel thresholds=N,N (N s)")
    assert ex.matches("styletrace: a=1 b=2.5", "styletrace: a=7 b=0.25")
    assert not ex.matches("styletrace: a=1 b=2", "styletrace: b=1 a=2")
    assert not ex.matches("styletrace: thresholds=0.1", "styletrace: thresholds=0.1,0.2")
    assert ex.matches("styletrace: error: ...", "styletrace: error: scene file 'x' does not exist")
    assert ex.matches("styletrace: levels=0.07,...", "styletrace: levels=0.07,0.18; firefly=4")
    assert ex.output_lines("\ra (0 s)\ra (1 s)\nb\n") == ["a (0 s)", "a (1 s)", "b"]
