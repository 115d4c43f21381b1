"""The browser preview's jobs: the page's render, the buffer a session records of it, its draft,
and the command line of each.

    job = page_job("cornell-box", style="cel", samples=16)      # what `styletrace render` runs
    p = prepare(job)          # p.page: resolved (split, method); p.recording, p.draft: jobs
    command(p.page, "cel", None, {"levels": "0.2,0.6"})        # that render's command line

The page's render is `styletrace render` at the page's settings: its samples split for the style
the page starts with and its denoising chosen (`pipeline.resolve`, as every front end's). The
session records it with the `identity` style, so that every style restyles its buffer: the same
camera samples, children, seed and denoising method (given, so that the recorded job splits and
denoises as the page's does), one camera sample per pass. Where the image denoiser finishes the
render (a style of one child), its footprint is the film's, which a restyle develops. The draft is
the recording job's (`Job.draft`) at `progressive.rules.draft_size`, denoised as auto would.
"""
from __future__ import annotations

import shlex
from dataclasses import dataclass, replace
from typing import Any

from styletrace.errors import UsageError
from styletrace.lookdev.record import scene_label
from styletrace.pipeline.denoising import Denoising
from styletrace.pipeline.job import Job
from styletrace.pipeline.resolve import Resolved, resolve
from styletrace.pipeline.terms import COMMAND_LINE
from styletrace.progressive.rules import DRAFT_QUALITY, PREVIEW_K, PREVIEW_QUALITY, draft_size

#: a built-in scene's film where the caller names no size
DEFAULT_SIZE = 256
#: the style the page starts with where the caller names none (its n sets the split)
DEFAULT_STYLE = "cel"


def page_job(scene: Any = None, *, style: str = DEFAULT_STYLE, params: dict | None = None,
             samples: int | None = None, spp: int | None = None, inner: int | None = None,
             width: int | None = None, height: int | None = None, seed: int = 0,
             denoise: str | None = None, max_camera_samples: int | None = None) -> Job:
    """The job of the page's render, as `styletrace render` would run it.

    Takes more than 7 parameters: each is one of `styletrace preview`'s flags (docs/preview.md).

    Args:
        scene: a built-in name or an XML file (None: the Cornell box); a built-in scene is
            DEFAULT_SIZE square unless sized.
        style, params: the style the page starts with and its parameters.
        samples, spp, inner: paths per pixel, camera samples per pixel, children (None: split).
        width, height, seed: the film and the seed. denoise: auto, expectation, image or off
            (None: the default). max_camera_samples: the buffer's cap (None: the default).

    Returns:
        The Job, in the command line's terms (the preview's flags are `render`'s).
    """
    builtin = scene is None or isinstance(scene, str) and not scene.lower().endswith(".xml")
    given = {"style": style, **(params or {})}
    if inner is not None:
        given["inner_samples"] = inner
    return Job(scene=scene, width=width or (DEFAULT_SIZE if builtin else None),
               height=height or (DEFAULT_SIZE if builtin else None), given=given, spp=spp,
               samples=samples, seed=seed, denoising=Denoising(denoise),
               max_camera_samples=max_camera_samples,
               terms=COMMAND_LINE)  # `styletrace preview` shares render's flags


@dataclass(frozen=True)
class Prepared:
    """What a preview session renders.

    Args:
        page: the page's render, resolved (its split, method and note).
        recording: the job the session records (`identity`, the page's counts and method).
        draft: the recording job's draft. scene, draft_scene: their loaded scenes.
        label: the scene's name on the page and in its command lines.
    """
    page: Resolved
    recording: Job
    draft: Job
    scene: Any
    draft_scene: Any
    label: str


def prepare(job: Job) -> Prepared:
    """Load the page's scene, resolve its render and make the jobs the session runs.

    Args:
        job: the page's job (`page_job`).

    Returns:
        The `Prepared` jobs.

    Raises:
        StyletraceError: a refusal of the render (one line, naming the preview's flags), or a split
            over the buffer's cap.
    """
    scene = job.load()
    page = resolve(job, scene)
    w, h = page.size
    if w * h * page.spp > job.cap:
        raise UsageError(f"{w}x{h} at {page.spp} spp is {w * h * page.spp} camera samples, over "
                         f"the preview's cap of {job.cap}; lower --spp, --samples or the size")
    footprint = "film" if page.method == "image" else job.denoising.footprint
    recording = job.with_(given={"style": "identity",
                                 "inner_samples": int(page.budget.children[0])},
                          spp=page.spp, samples=None, pass_spp=1,
                          denoising=replace(job.denoising, method=page.method,
                                            footprint=footprint))
    dw, dh = draft_size(w, h)
    draft = recording.with_(draft=True, width=dw, height=dh, denoising=Denoising(
        "auto", quality=DRAFT_QUALITY, footprint="film"))
    draft_scene = scene if (dw, dh) == (w, h) else job.load(dw, dh)
    return Prepared(page, recording, draft, scene, draft_scene, scene_label(job.scene))


def command(prepared: Prepared, style: str, estimator: str | None, params: dict[str, Any],
            draft: Any = None) -> str:
    """The `styletrace render` command line of the render a session ends with (its final image,
    restyled as the page shows it), or of its draft.

    Args:
        prepared: the session's jobs. style, estimator, params: what the page shows.
        draft: the draft's runner (`pipeline.runner.Runner`) for the draft's command, or None.

    Returns:
        The command line, quoted for a shell.
    """
    page = prepared.page
    runner = draft
    resolved = runner.resolved if runner is not None else None
    spp = 1 if resolved is not None else page.spp
    children = int((resolved or page).budget.children[0])
    w, h = resolved.size if resolved is not None else page.size
    method = resolved.method if resolved is not None else page.method
    words = ["styletrace", "render", prepared.label, "--style", style, "--inner", str(children),
             "--spp", str(spp), "--seed", str(page.job.seed), "--pass-spp", "1"]
    if estimator:
        words += ["--estimator", estimator]
    words += ["--denoise", method]
    if resolved is not None and method == "expectation":  # the draft's quick preview
        words += ["--coverage", str(PREVIEW_K), "--denoise-quality", PREVIEW_QUALITY]
    elif resolved is not None and method == "image":
        words += ["--denoise-quality", DRAFT_QUALITY]
    if method == "image":
        words += ["--denoise-footprint", "film"]
    words += ["--width", str(w), "--height", str(h)]
    for k, v in params.items():
        words += ["--set", f"{k}={v}"]
    return shlex.join(words + ["-o", "render.png"])


__all__ = ["page_job", "prepare", "command", "Prepared", "DEFAULT_SIZE", "DEFAULT_STYLE"]
