"""The docs are executable: every command and Python example of README.md and docs/*.md, found,
made small, and run (tests/docs/test_examples_*.py; issue 45).

What counts as an example
-------------------------
Code blocks are indented blocks (4 spaces, after a blank line) and fenced blocks (```, ```python,
```bash, ```sh, ```console); other fences (```xml, ...) are files, not commands, and are not read.
Inside a block, after joining lines that end in a backslash, each line is one of:

- a command: a line that starts (after `$ ` and `NAME=VALUE` assignments) with `styletrace`,
  `python`, `python3`, `.venv/bin/python`, `pip`, `bash dev.sh`, `blender`, `xvfb-run` or `ray`.
  Each command is one example. A line starting with `... ` is the command before it with more
  arguments. Lines after a `$ ` command, up to a blank line or the next `$ `, are what it prints.
- a printed line: a line starting with `styletrace: ` (also in inline code in the prose).
- anything else: a run of such lines (up to a blank line or a command) is a Python example when it
  mentions `styletrace` and parses, or starts like Python (`import`, `from`, `x = `, `styletrace.`)
  but does not parse; a ```python fence is one example as a whole. Other runs (formulas, listings,
  output) are not examples.

Each example is one test case named page:line (`cli.md:89`). The examples of one page run in order
in one temporary folder, so that `--buffer dragon.npz` and then `restyle dragon.npz` work; a case
run alone first runs the page's examples above it (their results are their own cases' business).

Small size (`small_argv`, `small_python`)
-----------------------------------------
- `styletrace render` and `styletrace preview`: `--width 16 --height 16` (given values replaced);
  `--spp` at most 4, `--samples` at most 16, `--pass-spp` and `--expansion-pass` at most 4,
  `--frames` at most 2, `--inner` at most 8 a level (adaptive `n0:max`: n0 at most 4, max at most
  16); where `--samples`, `--spp` and `--inner` are all given, `--samples` becomes their product.
- `styletrace fit`: `--iterations` at most 20 (20 where not given).
- `styletrace gallery`: `--size 16` and `--quick` (its own small mode: fewer reference samples,
  one equal-time repeat).
- `styletrace preview`: `--port` a free port; the command runs until its page answers, then gets
  Ctrl-C (SIGINT) and must exit 0 or 130.
- `bash dev.sh render [ARGS]`: run as the `styletrace render` that dev.sh execs after its setup
  (the default arguments read from dev.sh), since the setup installs system packages.
- `styletrace` runs as `python -m styletrace` on the source tree; `python` is this interpreter.
- Python: calls of `styletrace.render`, `styletrace.render_buffer` and `python_job` get
  `width=16, height=16` where their scene is a name or path (a given width or height becomes 16);
  another scene (a dict, an mi.Scene) goes through `_docs_small_scene`, which sizes a dict's
  films. The keywords `spp`, `samples`, `inner`, `inner_samples`, `pass_spp` and `iterations`
  (and dict keys of those names) are capped as the flags above. The program runs in a subprocess
  after `import styletrace`.
- Every example runs at the documented defaults: $STYLETRACE_DENOISE (which tests/conftest.py sets
  to off) is removed from its environment.

Files and names a user brings (`PLACEHOLDERS`)
----------------------------------------------
An example that names one of these, where no earlier example of its page made it, gets it written
into the page's folder first: `scene.xml`, `a.xml`, `b.xml`, `c.xml` (`SCENE_XML`: a small scene
with a `$depth` default, 16 x 16), `look.png` (a 16 x 16 target image for `fit`), `DIR` (a folder
name). In Python, the free names `scene` (an mi.Scene loaded from scene.xml) and `img_or_path`
("look.png"). A fragment of code that runs inside a kernel (`FRAGMENT_NAMES`: docs/estimators.md's
estimator call) runs without the statements that use the names the kernel around it would give.
`--ray` without an address starts a local Ray instance, as the docs say (about 6 s each).

Printed lines
-------------
A printed line is checked against the output of its command: the `$ ` command above it, else the
command of a marker `<!-- docs-test: prints: COMMAND -->` before it (the marker applies to the next
printed line; `<!-- docs-test: exit=2 prints: COMMAND -->` expects that exit status). A printed line
with neither fails. The line passes where some line the command prints (stdout or stderr, split at
newlines and carriage returns) has the same shape: numbers replaced with `N`, whitespace collapsed;
a shown line ending in `...` need only match the start.

A command that, made small, is one its page ran above is not run again (`styletrace gallery` with
and without `--quick`).

Skipped, each by a rule in `SKIPS` with its reason; synopses (a `[`, a `|` or a capitalised
placeholder among the arguments) and signatures (`*,` in a call that does not parse) are not run.
"""
from __future__ import annotations

import ast
import re
import shlex
import signal
import socket
import struct
import subprocess
import sys
import time
import urllib.request
import zlib
from dataclasses import dataclass, field
from pathlib import Path

from conftest import child_env  # tests/conftest.py: the source tree first on PYTHONPATH

ROOT = Path(__file__).resolve().parents[2]

#: the image size every render runs at
SIZE = 16
#: flag -> the most it may be (render and preview)
CAPS = {"--spp": 4, "--samples": 16, "--pass-spp": 4, "--expansion-pass": 4, "--frames": 2}
#: an inner count's caps: a fixed count, an adaptive count's n0 and its max
INNER_CAP, INNER_N0_CAP, INNER_MAX_CAP = 8, 4, 16
#: fit's gradient steps
ITERATIONS = 20
#: seconds an example may run
TIMEOUT = 180

SHELL_PROGRAMS = ("styletrace", "python", "python3", ".venv/bin/python", "pip", "bash", "blender",
                  "xvfb-run", "ray")
FENCES_READ = {"", "python", "py", "bash", "sh", "shell", "console"}

#: a scene file a user brings: 16 x 16, its own path integrator at a `$depth` default (as
#: `-D depth=3` / `defines={"depth": "3"}` in the docs set it), a box wall, a sphere, a light
SCENE_XML = """<scene version="3.0.0">
    <default name="depth" value="6"/>
    <integrator type="path">
        <integer name="max_depth" value="$depth"/>
    </integrator>
    <sensor type="perspective">
        <float name="fov" value="40"/>
        <transform name="to_world">
            <lookat origin="0, 0, 3.5" target="0, 0, 0" up="0, 1, 0"/>
        </transform>
        <sampler type="independent">
            <integer name="sample_count" value="16"/>
        </sampler>
        <film type="hdrfilm">
            <integer name="width" value="16"/>
            <integer name="height" value="16"/>
        </film>
    </sensor>
    <shape type="rectangle">
        <transform name="to_world">
            <scale value="2"/>
            <translate z="-1"/>
        </transform>
        <bsdf type="diffuse"/>
    </shape>
    <shape type="sphere">
        <float name="radius" value="0.5"/>
        <bsdf type="diffuse">
            <rgb name="reflectance" value="0.7, 0.3, 0.2"/>
        </bsdf>
    </shape>
    <shape type="rectangle">
        <transform name="to_world">
            <scale value="0.4"/>
            <rotate x="1" angle="90"/>
            <translate y="1.2"/>
        </transform>
        <emitter type="area">
            <rgb name="radiance" value="15"/>
        </emitter>
    </shape>
    <emitter type="constant">
        <rgb name="radiance" value="0.1"/>
    </emitter>
</scene>
"""


def png_bytes(width: int = SIZE, height: int = SIZE) -> bytes:
    """An 8-bit RGB PNG of a smooth gradient: a target image for `styletrace fit`."""
    rows = b"".join(
        b"\x00" + bytes(v for x in range(width)
                        for v in (255 * x // (width - 1), 255 * y // (height - 1), 96))
        for y in range(height))

    def chunk(kind: bytes, data: bytes) -> bytes:
        body = kind + data
        return struct.pack(">I", len(data)) + body + struct.pack(">I", zlib.crc32(body))

    header = struct.pack(">IIBBBBB", width, height, 8, 2, 0, 0, 0)
    return (b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", header) + chunk(b"IDAT", zlib.compress(rows))
            + chunk(b"IEND", b""))


def _write_scene(folder: Path, name: str) -> None:
    (folder / name).write_text(SCENE_XML)


def _write_look(folder: Path, name: str) -> None:
    (folder / name).write_bytes(png_bytes())


def _make_dir(folder: Path, name: str) -> None:
    (folder / name).mkdir(exist_ok=True)


#: file name -> (the name it is given, how it is made) for files a user brings
PLACEHOLDERS = {
    "scene.xml": ("scene.xml", _write_scene),
    "a.xml": ("a.xml", _write_scene),
    "b.xml": ("b.xml", _write_scene),
    "c.xml": ("c.xml", _write_scene),
    "look.png": ("look.png", _write_look),
    "DIR": ("dir", _make_dir),
}
#: Python names a user brings -> (the files they need, the code that defines them)
PYTHON_PLACEHOLDERS = {
    "scene": (("scene.xml",), "import mitsuba as mi\nstyletrace.init()\n"
                              "scene = mi.load_file('scene.xml')"),
    "img_or_path": (("look.png",), "img_or_path = 'look.png'"),
}
#: names a documented fragment takes from the code around it: statements that use them do not run
FRAGMENT_NAMES = {
    # SeriesEstimator.run inside an integrator's loop: the kernel's draw function, sampler, ...
    "docs/estimators.md": {"draw", "sampler", "uniform", "active"},
}


@dataclass
class Skip:
    """A kind of example that is not run, and why."""
    reason: str
    shell: str | None = None    # regex on the command as written
    python: str | None = None   # regex on the Python example


#: every example that does not run: short, each with its reason
SKIPS = [
    Skip("installs packages into the environment (network)", shell=r"^pip\b"),
    Skip("runs the whole test suite, this test among it", shell=r"^bash dev\.sh test\b"),
    Skip("runs a test suite", shell=r"-m pytest\b"),
    Skip("the Blender application and an X server, absent in CI (tests/blender runs the add-on "
         "as a module)", shell=r"^(blender|xvfb-run)\b"),
    Skip("Blender as a Python module lives in .venv-blender (tests/blender runs these steps)",
         python=r"^\s*import bpy\b"),
    Skip("a Ray cluster at an address (tests/distributed runs a local one)",
         shell=r"--ray [A-Za-z0-9.-]+:\d+", python=r"cluster=\"[A-Za-z0-9.-]+:\d+\""),
    Skip("downloads Mitsuba's, Dr.Jit's and OIDN's wheels with pip (network, about 10 s); "
         "tests/blender/test_extension.py builds and validates the zip",
         shell=r"-m styletrace\.blender\.extension\b"),
    Skip("continues a render killed part-way (the line above it finishes, leaving nothing to "
         "resume); tests/distributed/test_checkpoint.py kills one and resumes it",
         shell=r"--ray\b.*--resume\b"),
    Skip("benchmarks/ needs the panel of public scenes (docs/real_scenes.md), absent in CI, and "
         "rewrites docs/ and BENCHMARKS.md", shell=r"benchmarks/"),
]
#: printed lines not produced by a command: page -> why
PRINTED_ELSEWHERE = {
    "docs/blender.md": "printed by the Blender add-on inside Blender (tests/blender)",
}


@dataclass
class Example:
    """One example of a docs page.

    kind: "shell" (text: the command as written), "python" (text: the program), or "printed"
    (a printed line with its marker's command in `text`, None without one). `shown`: the printed
    lines it must reproduce, (line, text). `skip`: why it does not run (None: it runs).
    """
    page: str
    line: int
    kind: str
    text: str | None
    shown: list[tuple[int, str]] = field(default_factory=list)
    exit: int = 0
    skip: str | None = None

    @property
    def id(self) -> str:
        return f"{Path(self.page).name}:{self.line}"


# --- extraction -------------------------------------------------------------------------------

MARKER = re.compile(r"<!--\s*docs-test:\s*(.*?)\s*-->", re.S)
FENCE = re.compile(r"^(\s*)(`{3,}|~{3,})\s*([\w+-]*)")
INLINE_PRINTED = re.compile(r"`(styletrace: [^`]*)`")
ENV_ASSIGN = re.compile(r"^[A-Za-z_][A-Za-z0-9_]*=")
PYTHON_START = re.compile(
    r"^(import |from \S+ import |[\w.]+(\s*,\s*[\w.]+)*\s*=[^=]|styletrace\.)")


@dataclass
class _Block:
    line: int            # 1-based line of the block's first line
    lines: list[str]     # dedented
    fence: str | None    # the fence's language, None for an indented block


def _blocks(lines: list[str]) -> list[_Block]:
    """The code blocks of a page that may hold examples, and blanks the lines of every code block
    in `lines` (in place) so that the prose scan does not see them."""
    blocks, i, prev_blank = [], 0, True
    while i < len(lines):
        text = lines[i]
        m = FENCE.match(text)
        if m:
            indent, marks, lang = len(m.group(1)), m.group(2), m.group(3).lower()
            start, body = i + 1, []
            lines[i] = ""
            i += 1
            while i < len(lines) and lines[i].strip() != marks:
                body.append(lines[i][indent:] if lines[i][:indent].strip() == "" else lines[i])
                lines[i] = ""
                i += 1
            if i < len(lines):
                lines[i] = ""
            i += 1
            if lang in FENCES_READ:
                blocks.append(_Block(start + 1, body, lang))
            prev_blank = False
            continue
        if prev_blank and text.startswith("    ") and text.strip():
            start, body = i, []
            while i < len(lines) and (lines[i].startswith("    ") or not lines[i].strip()):
                body.append(lines[i][4:])
                lines[i] = ""
                i += 1
            while body and not body[-1].strip():
                body.pop()
            blocks.append(_Block(start + 1, body, None))
            prev_blank = False
            continue
        prev_blank = not text.strip()
        i += 1
    return blocks


def _logical(block: _Block) -> list[tuple[int, str]]:
    """(line, text) of a block's lines with backslash continuations joined."""
    out, i = [], 0
    while i < len(block.lines):
        start, text = block.line + i, block.lines[i]
        while text.rstrip().endswith("\\") and i + 1 < len(block.lines):
            i += 1
            text = text.rstrip()[:-1].rstrip() + " " + block.lines[i].strip()
        out.append((start, text))
        i += 1
    return out


def command_words(text: str) -> list[str]:
    """A command line's words, `$ `, comments and leading NAME=VALUE assignments kept apart by
    `split_env`; [] where the line does not parse as one."""
    try:
        return shlex.split(text, comments=True)
    except ValueError:
        return []


def split_env(words: list[str]) -> tuple[dict[str, str], list[str]]:
    """Leading NAME=VALUE words as an environment, and the rest."""
    env = {}
    while words and ENV_ASSIGN.match(words[0]):
        name, _, value = words[0].partition("=")
        env[name] = value
        words = words[1:]
    return env, words


def is_command(text: str) -> bool:
    """Whether a line is a shell command (rule in the module docstring)."""
    stripped = text.strip()
    if stripped.startswith("$ "):
        return True
    _, words = split_env(command_words(stripped))
    return bool(words) and words[0] in SHELL_PROGRAMS and (
        words[0] != "bash" or (len(words) > 1 and words[1] == "dev.sh"))


def is_synopsis(words: list[str]) -> bool:
    """A usage line rather than an example: `[`, `|` or a capitalised placeholder (NAME,
    KEY=VALUE, N, ...) among its arguments."""
    for w in words[1:]:
        if w in PLACEHOLDERS:
            continue
        if w.startswith("[") or "|" in w or re.fullmatch(r"[A-Z][A-Z0-9_]*(=[A-Z][A-Z0-9_]*)?", w):
            return True
    return False


def _python_kind(text: str) -> str | None:
    """"python" for a Python example, "signature" for a documented signature, None for neither."""
    if "styletrace" not in text:
        return None
    try:
        ast.parse(text)
        return "python"
    except SyntaxError:
        if re.search(r"\(\s*[^)]*\*,", text, re.S) or "**" in text:
            return "signature"
        return "python" if PYTHON_START.match(text.lstrip()) else None


def _skip_for(kind: str, text: str) -> str | None:
    """The reason of the first rule of SKIPS that matches (a command: without its NAME=VALUE
    words and comments)."""
    if kind == "shell":
        text = shlex.join(split_env(command_words(text))[1])
    else:
        try:
            text = ast.unparse(ast.parse(text))     # comments left out
        except SyntaxError:
            pass
    for rule in SKIPS:
        pattern = rule.shell if kind == "shell" else rule.python
        if pattern and re.search(pattern, text, re.M):
            return rule.reason
    return None


def extract(page: str, markdown: str) -> list[Example]:
    """Every example of one page, in page order (see the module docstring for the rules).

    Args:
        page: the page's path relative to the repository, e.g. "docs/cli.md".
        markdown: its text.
    """
    lines = markdown.split("\n")
    markers = []   # (line, exit, command) of `prints:` markers
    for m in MARKER.finditer(markdown):
        line = markdown.count("\n", 0, m.start()) + 1
        body = m.group(1)
        exit_status = 0
        em = re.match(r"exit=(\d+)\s+", body)
        if em:
            exit_status, body = int(em.group(1)), body[em.end():]
        if body.startswith("prints:"):
            markers.append((line, exit_status, body[len("prints:"):].strip()))
    blocks = _blocks(lines)          # blanks code in `lines`
    examples: list[Example] = []
    printed: list[tuple[int, str]] = []   # printed lines without a command of their own

    for block in blocks:
        if block.fence in ("python", "py"):
            text = "\n".join(block.lines)
            kind = _python_kind(text)
            if kind:
                examples.append(_python_example(page, block.line, text, kind))
            continue
        group: list[tuple[int, str]] = []
        last: Example | None = None     # the last `$ ` command, while its output follows

        def flush():
            if group:
                text = "\n".join(t for _, t in group)
                kind = _python_kind(text)
                if kind:
                    examples.append(_python_example(page, group[0][0], text, kind))
                group.clear()

        previous: Example | None = None
        for line, text in _logical(block):
            stripped = text.strip()
            if not stripped:
                flush()
                last = None
                continue
            if stripped.startswith("... ") and previous is not None:
                flush()
                last = None
                again = shlex.join(command_words(previous.text))    # its comment left out
                previous = _shell_example(page, line, again + " " + stripped[4:])
                examples.append(previous)
                continue
            if is_command(stripped):
                flush()
                dollar = stripped.startswith("$ ")
                previous = _shell_example(page, line, stripped[2:] if dollar else stripped)
                examples.append(previous)
                last = previous if dollar else None
                continue
            if last is not None:
                last.shown.append((line, stripped))
                continue
            if stripped.startswith("styletrace: "):
                flush()
                printed.append((line, stripped))
                continue
            group.append((line, text))
        flush()

    prose = "\n".join(lines)
    for m in INLINE_PRINTED.finditer(prose):
        printed.append((prose.count("\n", 0, m.start()) + 1, " ".join(m.group(1).split())))

    printed.sort()
    owner: dict[int, tuple[int, int, str]] = {}   # printed line -> its marker
    for marker in markers:       # a marker applies to the next printed line after it
        after = [line for line, _ in printed if line >= marker[0] and line not in owner]
        if after:
            owner[after[0]] = marker
    for line, text in printed:
        marker = owner.get(line)
        example = Example(page, line, "printed", marker[2] if marker else None, [(line, text)],
                          exit=marker[1] if marker else 0)
        if marker is None and page in PRINTED_ELSEWHERE:
            example.skip = PRINTED_ELSEWHERE[page]
        elif marker is not None:
            example.skip = _shell_skip(marker[2])
        examples.append(example)
    examples.sort(key=lambda e: e.line)
    return examples


def _shell_skip(text: str) -> str | None:
    words = split_env(command_words(text))[1]
    if not words:
        return None
    if is_synopsis(words):
        return "a synopsis: placeholders, not an example"
    return _skip_for("shell", text)


def _shell_example(page: str, line: int, text: str) -> Example:
    return Example(page, line, "shell", text, skip=_shell_skip(text))


def _python_example(page: str, line: int, text: str, kind: str) -> Example:
    skip = "a signature, not an example" if kind == "signature" else _skip_for("python", text)
    return Example(page, line, "python", text, skip=skip)


def _argv_key(argv: list[str]) -> tuple:
    """A command's words with its options in any order: (positionals, {(option, value)})."""
    positional, options, i = [], set(), 0
    while i < len(argv):
        if argv[i].startswith("-") and i + 1 < len(argv) and not argv[i + 1].startswith("-"):
            options.add((argv[i], argv[i + 1]))
            i += 2
        elif argv[i].startswith("-"):
            options.add((argv[i], None))
            i += 1
        else:
            positional.append(argv[i])
            i += 1
    return tuple(positional), frozenset(options)


def collect(pages: list[str]) -> list[Example]:
    """The examples of the given pages (paths relative to the repository), in page order; a
    command that, made small, is one an earlier example of its page runs is not run again."""
    out = []
    for page in pages:
        seen: dict[tuple, str] = {}
        for e in extract(page, (ROOT / page).read_text()):
            if e.kind == "shell" and e.skip is None:
                env, words = split_env(command_words(e.text))
                key = (tuple(sorted(env.items())), _argv_key(small_argv(words, port=0)))
                if key in seen:
                    e.skip = f"the same command as {seen[key]} once made small"
                seen.setdefault(key, e.id)
            out.append(e)
    return out


def all_pages() -> list[str]:
    """README.md and docs/*.md, relative to the repository."""
    return ["README.md"] + sorted(f"docs/{p.name}" for p in (ROOT / "docs").glob("*.md"))


#: the pages of each test file (tests/docs/test_examples_GROUP.py); pytest-xdist's loadfile gives
#: each file to one worker, so the groups are balanced by their run time
GROUPS = {
    "cli": ["README.md", "docs/cli.md", "docs/reliability.md", "docs/scenes.md",
            "docs/install.md", "docs/look.md", "docs/styles.md"],
    "lookdev": ["docs/lookdev.md", "docs/preview.md", "docs/denoise.md", "docs/python.md",
                "docs/blender.md"],
    "guide": ["docs/guide.md"],     # the gallery: about 40 s with its kernels not yet compiled
    "methods": ["docs/adaptive.md", "docs/estimators.md", "docs/lines.md", "docs/llat.md",
                "docs/reuse.md", "docs/ray.md", "docs/real_scenes.md", "docs/how_it_works.md",
                "docs/architecture.md", "docs/passes.md", "docs/temporal.md",
                "docs/light_groups.md"],
}


# --- small size -------------------------------------------------------------------------------

def small_inner(value: str) -> str:
    """An `--inner` value capped: `16` -> `8`, `4:64` -> `4:16`, `8,8` -> `8,8`."""
    def level(text: str) -> str:
        if ":" in text:
            n0, _, top = text.partition(":")
            n0 = min(int(n0), INNER_N0_CAP)
            return f"{n0}:{max(n0, min(int(top), INNER_MAX_CAP))}"
        return str(min(int(text), INNER_CAP))
    try:
        return ",".join(level(t) for t in str(value).split(","))
    except ValueError:
        return str(value)


def _paths(inner: str) -> int | None:
    """Paths per camera sample of a fixed or adaptive inner value (n0 counts), None if unknown."""
    total = 1
    try:
        for t in str(inner).split(","):
            total *= int(t.partition(":")[0])
    except ValueError:
        return None
    return total


def _option(words: list[str], name: str) -> int | None:
    """Index of the value of option `name` in words (`--x v` or `--x=v` split first)."""
    for i, w in enumerate(words[:-1]):
        if w == name:
            return i + 1
    return None


def _set_option(words: list[str], name: str, value: str) -> None:
    i = _option(words, name)
    if i is None:
        words.extend([name, value])
    else:
        words[i] = value


def _cap_option(words: list[str], name: str, cap: int) -> None:
    i = _option(words, name)
    if i is not None:
        try:
            words[i] = str(min(int(words[i]), cap))
        except ValueError:
            pass


def dev_sh_render_args() -> list[str]:
    """The arguments `bash dev.sh render` gives `styletrace render` without arguments of its own."""
    m = re.search(r"^\s*set -- (.*?)$", (ROOT / "dev.sh").read_text(), re.M)
    return shlex.split(m.group(1)) if m else []


def small_argv(words: list[str], port: int | None = None) -> list[str]:
    """A command's words made small (rules in the module docstring): the program as it runs
    (`python -m styletrace`, this interpreter), the placeholders' names, the small flags."""
    words = [PLACEHOLDERS[w][0] if w in PLACEHOLDERS else w for w in words]
    split = []
    for w in words:   # --flag=value -> --flag value
        if w.startswith("--") and "=" in w and not w.startswith("--set"):
            split.extend(w.split("=", 1))
        else:
            split.append(w)
    words = split
    if words[:3] == ["bash", "dev.sh", "render"]:
        words = ["styletrace", "render", *(words[3:] or dev_sh_render_args())]
    if words[0] in ("python", "python3", ".venv/bin/python"):
        return [sys.executable, *words[1:]]
    if words[0] != "styletrace":
        return words
    sub = words[1] if len(words) > 1 else ""
    if sub in ("render", "preview"):
        _set_option(words, "--width", str(SIZE))
        _set_option(words, "--height", str(SIZE))
        for name, cap in CAPS.items():
            _cap_option(words, name, cap)
        i = _option(words, "--inner")
        if i is not None:
            words[i] = small_inner(words[i])
        si, pi = _option(words, "--samples"), _option(words, "--spp")
        if si is not None and pi is not None and i is not None and _paths(words[i]):
            words[si] = str(int(words[pi]) * _paths(words[i]))
    if sub == "preview":
        _set_option(words, "--port", str(port if port is not None else free_port()))
    if sub == "fit":
        i = _option(words, "--iterations")
        _set_option(words, "--iterations",
                    str(min(int(words[i]), ITERATIONS)) if i is not None else str(ITERATIONS))
    if sub == "gallery":
        _set_option(words, "--size", str(SIZE))
        if "--quick" not in words:
            words.append("--quick")
    return [sys.executable, "-m", "styletrace", *words[1:]]


#: the function a Python example's non-constant scene goes through: a scene dict's films sized
SMALL_SCENE = "_docs_small_scene"
SMALL_SCENE_CODE = f"""
def {SMALL_SCENE}(scene):
    # tests/docs: a scene dict's films at {SIZE} x {SIZE} (width=/height= refuse dicts)
    if isinstance(scene, dict):
        for value in scene.values():
            film = value.get("film") if isinstance(value, dict) else None
            if isinstance(film, dict):
                film["width"] = film["height"] = {SIZE}
    return scene
"""
KEYWORD_CAPS = {"spp": CAPS["--spp"], "samples": CAPS["--samples"], "inner_samples": INNER_CAP,
                "iterations": ITERATIONS, "pass_spp": CAPS["--pass-spp"]}


class _Small(ast.NodeTransformer):
    """Caps the count keywords and sizes the render calls of a Python example."""

    @staticmethod
    def _capped(name: str, node: ast.expr) -> ast.expr:
        if not isinstance(node, ast.Constant):
            return node
        if name == "inner" and isinstance(node.value, (int, str)) and not isinstance(
                node.value, bool):
            text = small_inner(str(node.value))
            return ast.Constant(int(text) if isinstance(node.value, int) else text)
        if name in KEYWORD_CAPS and isinstance(node.value, int) and not isinstance(
                node.value, bool):
            return ast.Constant(min(node.value, KEYWORD_CAPS[name]))
        return node

    def visit_Call(self, node: ast.Call) -> ast.Call:
        self.generic_visit(node)
        for kw in node.keywords:
            if kw.arg:
                kw.value = self._capped(kw.arg, kw.value)
        func = node.func
        name = func.attr if isinstance(func, ast.Attribute) else getattr(func, "id", None)
        owner = func.value if isinstance(func, ast.Attribute) else None
        styletrace_call = (isinstance(owner, ast.Name) and owner.id == "styletrace"
                           and name in ("render", "render_buffer")) or (
            isinstance(func, ast.Name) and name == "python_job")
        if styletrace_call:
            scene = node.args[0] if node.args else next(
                (kw.value for kw in node.keywords if kw.arg == "scene"), None)
            if scene is None or isinstance(scene, ast.Constant):
                node.keywords = [kw for kw in node.keywords if kw.arg not in ("width", "height")]
                node.keywords[:0] = [ast.keyword("width", ast.Constant(SIZE)),
                                     ast.keyword("height", ast.Constant(SIZE))]
            else:   # a dict or an mi.Scene, which width/height do not resize
                small = ast.Call(ast.Name(SMALL_SCENE, ast.Load()), [scene], [])
                if node.args:
                    node.args[0] = small
                for kw in node.keywords:
                    if kw.arg in ("width", "height"):      # given: the small size
                        kw.value = ast.Constant(SIZE)
                    elif kw.arg == "scene":
                        kw.value = small
        kws = {kw.arg: kw for kw in node.keywords if kw.arg}
        if {"samples", "spp", "inner"} <= set(kws):
            spp, inner = kws["spp"].value, kws["inner"].value
            if isinstance(spp, ast.Constant) and isinstance(inner, ast.Constant):
                paths = _paths(inner.value)
                if paths:
                    kws["samples"].value = ast.Constant(spp.value * paths)
        return node

    def visit_Dict(self, node: ast.Dict) -> ast.Dict:
        self.generic_visit(node)
        node.values = [self._capped(k.value, v) if isinstance(k, ast.Constant)
                       and isinstance(k.value, str) else v
                       for k, v in zip(node.keys, node.values)]
        return node


def free_names(tree: ast.AST) -> set[str]:
    """Names a program reads but neither assigns, imports nor finds among the builtins."""
    loaded, bound = set(), set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Name):
            (loaded if isinstance(node.ctx, ast.Load) else bound).add(node.id)
        elif isinstance(node, ast.alias):
            bound.add((node.asname or node.name).split(".")[0])
        elif isinstance(node, (ast.FunctionDef, ast.ClassDef)):
            bound.add(node.name)
        elif isinstance(node, ast.arg):
            bound.add(node.arg)
    import builtins
    return loaded - bound - set(dir(builtins))


def small_python(page: str, text: str) -> tuple[str, list[str]]:
    """A Python example as it runs: the fragment's outside statements dropped, the preamble
    (`import styletrace`, the placeholders it reads), the counts capped and the renders sized.

    Returns:
        The program, and the placeholder files it needs.
    """
    tree = ast.parse(text)
    outside = FRAGMENT_NAMES.get(page, set())
    if outside:
        tree.body = [s for s in tree.body if not (free_names(ast.Module([s], [])) & outside)]
    tree = ast.fix_missing_locations(_Small().visit(tree))
    free = free_names(tree)
    preamble, files = ["import styletrace"], []
    for name, (needs, code) in PYTHON_PLACEHOLDERS.items():
        if name in free:
            preamble.append(code)
            files.extend(needs)
    if "mi" in free and "import mitsuba as mi" not in "\n".join(preamble):
        preamble.append("import mitsuba as mi\nstyletrace.init()")
    if SMALL_SCENE in free:
        preamble.append(SMALL_SCENE_CODE.strip())
    return "\n".join(preamble) + "\n\n" + ast.unparse(tree) + "\n", files


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


# --- printed lines ----------------------------------------------------------------------------

NUMBER = re.compile(r"(?<![\w.])[-+]?(\d+(\.\d*)?|\.\d+)([eE][-+]?\d+)?(?![\w])")


def shape(line: str) -> str:
    """A printed line with its numbers replaced with N and its whitespace collapsed."""
    return " ".join(NUMBER.sub("N", line).split())


def matches(shown: str, printed: str) -> bool:
    """Whether a program's line has the shape of a line the docs show (`...` at its end: a
    prefix)."""
    want, got = shape(shown), shape(printed)
    if want.endswith("..."):
        return got.startswith(want[:-3].rstrip())
    return got == want


def output_lines(text: str) -> list[str]:
    return [s.strip() for s in re.split(r"[\r\n]", text) if s.strip()]


# --- running ----------------------------------------------------------------------------------

def child_environment(extra: dict[str, str] | None = None) -> dict[str, str]:
    """The source tree first on PYTHONPATH, the documented defaults ($STYLETRACE_DENOISE
    removed), and the example's own NAME=VALUE words."""
    env = child_env()
    env.pop("STYLETRACE_DENOISE", None)
    env.update(extra or {})
    return env


@dataclass
class Result:
    argv: list[str]
    returncode: int | None
    stdout: str
    stderr: str
    program: str | None = None   # a Python example's program as it ran
    note: str = ""


def provide(folder: Path, text: str, names: list[str] = ()) -> None:
    """Writes the placeholder files `text` names (or `names` lists) that `folder` lacks."""
    for name, (given, make) in PLACEHOLDERS.items():
        named = name in names or re.search(rf"(?<![\w/.-]){re.escape(name)}(?![\w.])", text)
        if named and not (folder / given).exists():
            make(folder, given)


def run_shell(text: str, folder: Path) -> Result:
    env, words = split_env(command_words(text))
    provide(folder, " ".join(words))
    argv = small_argv(words)
    if argv[3:4] == ["preview"]:
        return _run_preview(argv, folder, env)
    try:
        r = subprocess.run(argv, cwd=folder, env=child_environment(env), capture_output=True,
                           text=True, timeout=TIMEOUT)
    except subprocess.TimeoutExpired as exc:
        return Result(argv, None, _text(exc.stdout), _text(exc.stderr),
                      note=f"timed out after {TIMEOUT} s")
    return Result(argv, r.returncode, r.stdout, r.stderr)


def _text(data) -> str:
    return data.decode(errors="replace") if isinstance(data, bytes) else (data or "")


def _run_preview(argv: list[str], folder: Path, env: dict[str, str]) -> Result:
    """Starts a preview, waits until its page answers, then stops it with Ctrl-C."""
    port = argv[argv.index("--port") + 1]
    out, err = folder / "preview.out", folder / "preview.err"
    with open(out, "w") as fo, open(err, "w") as fe:
        proc = subprocess.Popen(argv, cwd=folder, env=child_environment(env), stdout=fo,
                                stderr=fe)
        note, deadline = "", time.monotonic() + TIMEOUT
        while True:
            if proc.poll() is not None:
                note = "exited before its page answered"
                break
            try:
                with urllib.request.urlopen(f"http://127.0.0.1:{port}/", timeout=5) as page:
                    if page.status == 200 and b"<" in page.read():
                        break
            except OSError:
                pass
            if time.monotonic() > deadline:
                note = f"its page did not answer within {TIMEOUT} s"
                break
            time.sleep(0.25)
        if proc.poll() is None:
            proc.send_signal(signal.SIGINT)
            try:
                proc.wait(30)
            except subprocess.TimeoutExpired:
                proc.kill()
                proc.wait()
                note = note or "did not stop within 30 s of Ctrl-C"
    code = proc.returncode
    if not note and code in (0, 130, -signal.SIGINT):
        code = 0      # stopped by Ctrl-C as a user stops it
    return Result(argv, code, out.read_text(), err.read_text(), note=note)


def run_python(page: str, line: int, text: str, folder: Path) -> Result:
    try:
        program, files = small_python(page, text)
    except SyntaxError as exc:
        return Result([], 1, "", f"SyntaxError: {exc}", program=text)
    provide(folder, text, files)
    path = folder / f"example_{line}.py"
    path.write_text(program)
    argv = [sys.executable, path.name]
    try:
        r = subprocess.run(argv, cwd=folder, env=child_environment(), capture_output=True,
                           text=True, timeout=TIMEOUT)
    except subprocess.TimeoutExpired as exc:
        return Result(argv, None, _text(exc.stdout), _text(exc.stderr), program=program,
                      note=f"timed out after {TIMEOUT} s")
    return Result(argv, r.returncode, r.stdout, r.stderr, program=program)


def run(example: Example, folder: Path) -> Result:
    if example.kind == "python":
        return run_python(example.page, example.line, example.text, folder)
    return run_shell(example.text, folder)


def report(example: Example, result: Result, problem: str, lines: int = 20) -> str:
    """A failure message: the example, what ran, its exit status, the end of its stderr."""
    parts = [f"{example.page}:{example.line}: {problem}", f"as written: {example.text}"]
    if result.program is not None:
        parts.append("program as run:\n" + result.program.rstrip())
    if result.argv:
        parts.append("as run: " + shlex.join(result.argv))
    parts.append(f"exit status: {result.returncode}" + (f" ({result.note})" if result.note
                                                         else ""))
    tail = output_lines(result.stderr)[-lines:]
    parts.append("stderr (last lines):\n" + "\n".join("    " + t for t in tail))
    if not result.stderr.strip():
        parts.append("stdout (last lines):\n" + "\n".join(
            "    " + t for t in output_lines(result.stdout)[-lines:]))
    return "\n".join(parts)


def check(example: Example, result: Result) -> list[str]:
    """The failures of one example's run: its exit status, and each shown line it did not print."""
    problems = []
    if result.note or result.returncode != example.exit:
        problems.append(report(example, result, f"exit status {result.returncode}, expected "
                                                 f"{example.exit}"))
    printed = output_lines(result.stdout) + output_lines(result.stderr)
    for line, shown in example.shown:
        if any(matches(shown, p) for p in printed):
            continue
        head = " ".join(shape(shown).split()[:3])
        near = [p for p in printed if shape(p).startswith(head)] or printed[-8:]
        problems.append(
            f"{example.page}:{line}: the docs show\n    {shown}\nas printed by\n    "
            f"{shlex.join(result.argv)}\nwhose lines of that kind are\n"
            + "\n".join("    " + p for p in near)
            + f"\n(compared as shapes: {shape(shown)!r})")
    return problems


class Pages:
    """One temporary folder per page; each page's examples run in page order."""

    def __init__(self, root: Path):
        self.root = root
        self.done: dict[str, set[int]] = {}

    def folder(self, page: str) -> Path:
        path = self.root / page.replace("/", "_")
        path.mkdir(parents=True, exist_ok=True)
        return path

    def run(self, example: Example, examples: list[Example]) -> Result:
        """Runs the page's earlier examples not yet run, then `example`."""
        done = self.done.setdefault(example.page, set())
        folder = self.folder(example.page)
        for before in examples:
            if (before.page == example.page and before.line < example.line
                    and before.line not in done and before.skip is None and before.text):
                run(before, folder)
                done.add(before.line)
        done.add(example.line)
        return run(example, folder)


def run_case(example: Example, examples: list[Example], pages: Pages) -> None:
    """One test case: skips what SKIPS skips, runs the example, fails with every problem."""
    import pytest

    if example.skip:
        pytest.skip(example.skip)
    if example.text is None:
        pytest.fail(f"{example.page}:{example.line}: the docs show the printed line\n    "
                    f"{example.shown[0][1]}\nwith no command: put `<!-- docs-test: prints: "
                    f"COMMAND -->` before it", pytrace=False)
    problems = check(example, pages.run(example, examples))
    if problems:
        pytest.fail("\n\n".join(problems), pytrace=False)
