"""`samples` has one meaning (issue 44): paths per pixel, the render's cost whatever the style (as
Cycles' Samples). Camera samples are called camera samples, children per stylized vertex inner
samples (`inner_samples`, --inner). Read from what users see: the command line's flags and their
help, the Python API's keywords, the integrator's properties, the preview's JSON, the errors of the
budget (Blender's labels: tests/blender/test_vocabulary.py)."""
import inspect
import re

import pytest

from styletrace.frontends import cli

#: a count of camera samples must say so: "samples per pixel" or "samples per pass" only after
#: "camera"
COUNT = re.compile(r"(\w+)\s+samples per (pixel|pass)", re.IGNORECASE)
#: where a name holds "samples", what it may be
NAMES = {"samples", "inner_samples", "line_samples", "camera_samples", "max_camera_samples",
         "cap_camera_samples", "scene_samples", "least_camera_samples",
         # not a count: what draws the random numbers (Mitsuba's word; Blender's "Sampling pattern")
         "sampler"}


def unqualified_counts(text: str) -> list[str]:
    """The phrases of `text` that count samples per pixel or per pass without saying camera."""
    return [m.group(0) for m in COUNT.finditer(text) if m.group(1).lower() != "camera"]


def helps(parser, prefix=""):
    """(command, option strings, help) of every option of the parser and its subcommands."""
    for action in parser._actions:
        if isinstance(getattr(action, "choices", None), dict):
            for name, sub in action.choices.items():
                yield from helps(sub, f"{prefix}{name} ")
        else:
            yield prefix.strip(), tuple(action.option_strings), action.help or ""


def test_the_command_line_says_samples_for_paths_per_pixel_only():
    rows = list(helps(cli.build_parser()))
    for command, flags, text in rows:
        assert not unqualified_counts(text), (command, flags, text)
        if "--samples" in flags:
            assert "paths per pixel" in text, (command, text)
        if "--spp" in flags:
            assert text.startswith("camera samples per pixel"), (command, text)
        for flag in flags:
            assert "sample" not in flag or flag in ("--samples", "--sampler"), flag
    assert {c for c, f, _ in rows if "--samples" in f} == {"render", "preview"}


def test_the_python_keywords():
    import styletrace
    from styletrace.lookdev.record import render_buffer
    render = styletrace.render
    for fn in (render, render_buffer):
        for name in inspect.signature(fn).parameters:
            assert "sample" not in name or name in NAMES, (fn.__name__, name)
    doc = inspect.getdoc(render)
    assert "samples: paths per pixel" in doc
    assert not unqualified_counts(doc)


def test_the_integrator_properties():
    from styletrace.config import settings
    for p in settings.PROPERTIES:
        assert "sample" not in p.name or p.name in NAMES, p.name
        assert not unqualified_counts(p.doc or ""), (p.name, p.doc)


def test_the_budgets_refusal_speaks_the_callers_words():
    """The one refusal of the split names samples, spp and inner as the caller does (the
    budget's own tests: tests/pipeline/test_budget.py)."""
    from styletrace.errors import UsageError
    from styletrace.pipeline import terms
    from styletrace.pipeline.budget import Request, split
    request = Request(scene_samples=64, samples=64, camera_samples=4, children=(8,),
                      style_children=16, terms=terms.COMMAND_LINE)
    with pytest.raises(UsageError, match=r"^--samples 64 with --spp 4 and --inner 8 "):
        split(request)


def test_the_previews_json():
    """The preview's state: `samples` is the render's paths per pixel; camera samples are named
    so."""
    pytest.importorskip("starlette")
    import styletrace
    from styletrace.preview.jobs import page_job
    from styletrace.preview.session import Session
    styletrace.init()
    s = Session(page_job("cornell-box", style="cel", width=16, height=16, samples=32,
                         denoise="off"))
    from styletrace.preview import jobs
    s.prepared = jobs.prepare(s.job)  # resolved, nothing rendered
    state = s.state()
    for key in state:
        assert "sample" not in key or key in NAMES | {"bytes_per_camera_sample"}, key
    assert state["samples"] == 32 == state["spp"] * state["children"]
    assert state["camera_samples"] == 0  # none recorded yet
    assert state["cap_camera_samples"] == s.job.cap
    for text in (state["note"], *(f["label"] for f in state["images"])):
        assert not unqualified_counts(text), text
