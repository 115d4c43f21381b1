"""Resolving a `Job`, once: the scene loaded, its own integrator settings merged, the denoising
method chosen, the sample budget split, `auto` values pinned.

    r = resolve(Job(scene="scene.xml", given={"style": "cel"}, samples=64))
    r.scene, r.integrator, r.spp, r.lanes, r.auto   # what `execute` runs; auto: the values pinned
    r.budget, r.method, r.note                      # the split (`budget.Split`), the denoising

The integrator is a prebuilt one as it is; else the given values laid over the scene's own
`stylized` integrator (also one nested in `moment` or `aov`); else over the scene's carried
settings (`carried`) with the job's default style. Then, in this order and only here:
the denoising method is chosen from the job's `denoising` and the request
(`denoising.choose_method`: it reads the request, not a split); the job's samples (else the
scene's sample count) are split into camera samples and children for that method
(`budget.split`: at most `budget.CHILDREN` children where the expectation is denoised, within its
buffer's cap; a draft asks for one camera sample of those children, `budget.draft_request`); a
count the budget chooses replaces the integrator's default (`with_inner`; a count
given, by the caller or the scene file, is kept); its `auto` values are pinned on this scene
(`scene.defaults.resolve_defaults`), with the firefly control where it denoises. Every route that
renders the result draws the same image. Design: docs/design/render_pipeline.md.
"""
from __future__ import annotations

from dataclasses import dataclass, replace
from typing import Any

from styletrace.config import settings as S
from styletrace.gate import mi
from styletrace.kernel.data_passes import parse_passes
from styletrace.kernel.error_aovs import has_error_aovs
from styletrace.kernel.integrator import StylizedIntegrator
from styletrace.kernel.mist import parse_mist
from styletrace.pipeline.budget import Request, Split, draft_request, split
from styletrace.pipeline.carried import carried_settings, nested_stylized
from styletrace.pipeline.denoising import FIREFLY_K, choose_method
from styletrace.pipeline.job import Job
from styletrace.pipeline.passes import pass_count, pin_auto_values
from styletrace.pipeline.sizing import lanes_per_pass
from styletrace.scene.arguments import SEED_MAX, SPP_MAX, check_integrator, whole
from styletrace.scene.defaults import ScenePilot, pin_firefly, unique_styled
from styletrace.scene.loading import scene_spp
from styletrace.scene.plugins import init


@dataclass(frozen=True)
class Resolved:
    """A job with its scene loaded, its denoising chosen, its samples split and its integrator
    final: everything a run needs.

    Args:
        job: the job. scene: its loaded scene. integrator: its integrator, auto values pinned.
        budget: the samples split into camera samples x children (`budget.Split`).
        lanes: camera samples per launch. method: expectation, image or off (`choose_method`).
        note: why auto did not denoise ('' where it did, or was not asked to).
        auto: the values chosen here, one line: the split first ('' if none).
        lanes_note: why the device's pass size is below its default, if it is.
        pilot: the scene-defaults pilot the auto values came from (the recorder reuses it).
    """
    job: Job
    scene: mi.Scene
    integrator: mi.Integrator
    budget: Split
    lanes: int
    method: str = "off"
    note: str = ""
    auto: str = ""
    lanes_note: str | None = None
    pilot: ScenePilot | None = None

    @property
    def spp(self) -> int:
        """Camera samples per pixel (the split's)."""
        return self.budget.camera_samples

    @property
    def size(self) -> tuple[int, int]:
        size = self.scene.sensors()[0].film().crop_size()
        return int(size[0]), int(size[1])

    @property
    def launches(self) -> int:
        """How many kernel launches the passes make (`passes.pass_count`): what a progress bar
        counts."""
        return pass_count(self.scene, self.spp, self.lanes, pass_spp=self.job.pass_spp,
                          grow=self.job.pass_growth)


def job_integrator_values(scene: mi.Scene, job: Job) -> dict[str, Any] | None:
    """The property values of the job's integrator on this scene (`settings.refine_values`).

    Args:
        scene: the scene loaded from `job.scene`.
        job: the job: its given values, its scene source and defines, its default style.

    Returns:
        The given values laid over the scene's own `stylized` values (also one nested in a
        wrapper), else over its carried settings with the default style; None where the scene's own
        `stylized` integrator is used as it is (nothing given).
    """
    own = scene.integrator()
    given = dict(job.given)
    if isinstance(own, StylizedIntegrator):
        return S.refine_values(own.values, given) if given else None
    # `stylized` inside `moment` or `aov`: its values
    nested = nested_stylized(job.scene, job.defines)
    if nested is not None:
        return S.refine_values(nested, given)
    base = {"style": job.default_style, **carried_settings(scene, job.scene, job.defines)}
    return S.refine_values(base, given)


def choose_integrator(scene: mi.Scene, job: Job) -> mi.Integrator:
    """The job's integrator before its `auto` values are pinned (see the module doc).

    Args:
        scene: the scene loaded from `job.scene`.
        job: the job: its prebuilt integrator, else its values (`job_integrator_values`).

    Returns:
        The prebuilt integrator as it is, or a `StylizedIntegrator` built from the values.
    """
    if job.integrator is not None:
        return job.integrator
    values = job_integrator_values(scene, job)
    # from the values, also for the scene's own integrator as it is: Mitsuba's object resolves auto
    # values in its own `render` (scene/standalone.py); the pipeline pins them once, here, for
    # every route
    return StylizedIntegrator.from_values(scene.integrator().values if values is None else values)


def budget_request(job: Job, integrator: mi.Integrator, scene_samples: int,
                   scene: mi.Scene | None = None) -> Request:
    """What the job, its integrator and its scene say about the render's cost (`budget.Request`).

    Args:
        job: the job (its samples, spp and terms).
        integrator: the job's integrator before its auto values are pinned.
        scene_samples: the scene's sample count (the budget where the job names no samples).
        scene: the scene, whose `styled` BSDFs' own counts are the request's `object_children`
            (None: none counted).

    Returns:
        The request, not yet denoised. The children count as given where the integrator's values
        name `inner_samples` (the caller's, the scene file's own `stylized`), and for a prebuilt
        integrator of another class; an integrator without styles draws no children. With error
        AOVs an auto spp is at least 2 (their variance; `runner.Runner.check`).
    """
    least = 2 if has_error_aovs(integrator) else 1
    counts = dict(scene_samples=scene_samples, samples=job.samples, camera_samples=job.spp,
                  least_camera_samples=least, terms=job.terms)
    if not isinstance(integrator, StylizedIntegrator):
        return Request(**counts)
    s = integrator.settings
    fixed = "inner_samples" in integrator.values or type(integrator) is not StylizedIntegrator
    return Request(**counts, children=s.slot.inner if fixed else None,
                   style_children=s.slot.style.default_inner, levels=s.stylize_depth,
                   object_children=object_children(scene))


def object_children(scene: mi.Scene | None) -> int:
    """The most children a `styled` BSDF of `scene` draws at the first stylized level (n0 of an
    adaptive count; 0 for closed-form styles, for no styled BSDF and for None)."""
    if scene is None:
        return 0
    counts = [0 if b.slot.style.closed_form else int(b.slot.n(0)) for b in unique_styled(scene)]
    return max(counts, default=0)


def with_inner(integrator: StylizedIntegrator, inner: tuple[int, ...]) -> StylizedIntegrator:
    """`integrator` with other children counts, where they differ (its other values kept).

    Args:
        integrator: a `stylized` integrator. inner: the counts, one for every level or one per
            level.

    Returns:
        `integrator` itself where its counts are `inner`, else a new one of its values.
    """
    if tuple(integrator.settings.slot.inner) == tuple(inner):
        return integrator
    counts = ",".join(str(n) for n in inner)
    return StylizedIntegrator.from_values({**integrator.values, "inner_samples": counts})


def lanes_for(job: Job) -> tuple[int, str | None]:
    """Camera samples per pass of a job: the job's, else the device's (`sizing`).

    Args:
        job: the job; its `lanes_per_pass`, where set, wins.

    Returns:
        (lanes, note): the note says why the device's size is below its default, else None.
    """
    if job.lanes_per_pass is not None:
        return int(job.lanes_per_pass), None
    return lanes_per_pass(init())


def with_firefly(scene: mi.Scene, integrator: mi.Integrator, method: str,
                 pilot: ScenePilot | None) -> tuple[mi.Integrator, str]:
    """The firefly control a render of `method` gets at its default: on where it denoises, unless
    `firefly` was given or error AOVs (which describe the paper's estimator) are on.

    Args:
        scene: the scene. integrator: the render's integrator. method: the chosen method.
        pilot: the scene-defaults pilot to measure the control's floor with (None: a new one).

    Returns:
        (the integrator, with firefly = FIREFLY_K pinned where it applies; the note naming it).
    """
    if method == "off" or not isinstance(integrator, StylizedIntegrator):
        return integrator, ""
    s = integrator.settings
    if s.firefly is not None or s.aovs:
        return integrator, ""
    return pin_firefly(scene, integrator, pilot, FIREFLY_K)


def resolve(job: Job, scene: mi.Scene | None = None, local: bool = True) -> Resolved:
    """Resolve a job once: load its scene, choose its integrator and its denoising, split its
    samples, pin its `auto` values (the module doc).

    Args:
        job: the job to resolve.
        scene: the scene already loaded from `job.scene` (None: loaded here).
        local: the render runs in one process (a denoiser needs that; on Ray auto does not
            denoise).

    Returns:
        The `Resolved` job.

    Raises:
        UsageError: a bad spp, samples, seed, integrator or data pass, in the job's terms, or
            samples, spp and inner that disagree (`budget.split`).
    """
    t = job.terms
    # the data passes' names checked once, here: the run reads them as a tuple
    job = replace(job, data_passes=parse_passes(job.data_passes, t.name("passes")),
                  mist=parse_mist(job.mist, t.name("mist")))
    if job.spp is not None:
        whole(t.name("spp"), job.spp, 1, SPP_MAX)
    whole(t.name("seed"), job.seed, 0, SEED_MAX)
    check_integrator(job.integrator)
    if job.samples is not None:
        whole(t.name("samples"), job.samples, 1, SPP_MAX)
    if scene is None:
        scene = job.load()
    chosen = choose_integrator(scene, job)
    request = budget_request(job, chosen, scene_spp(scene), scene)
    method, note = choose_method(scene, chosen, request, job.denoising, local, job.cap)
    expectation = method == "expectation"
    if expectation:  # g meets the denoised expectation, within what its buffer holds
        w, h = (int(v) for v in scene.sensors()[0].film().crop_size())
        budget = split(replace(request, denoised=True), job.cap // (w * h))
    else:
        budget = split(request)
    if job.draft:  # a glimpse: the draft's own request, one camera sample of these children
        budget = split(draft_request(budget))
    if isinstance(chosen, StylizedIntegrator):
        chosen = with_inner(chosen, budget.children)
    # one pilot for the auto values, the firefly floor and, with --buffer, the recorder (it traces
    # only if a value needs it)
    pilot = ScenePilot(scene, chosen.settings) if isinstance(chosen, StylizedIntegrator) else None
    integrator, auto = pin_auto_values(scene, chosen, pilot)
    integrator, firefly = with_firefly(scene, integrator, method, pilot)
    auto = "; ".join(a for a in (budget.note, auto, firefly) if a)
    lanes, lanes_note = lanes_for(job)
    return Resolved(job, scene, integrator, budget, lanes, method, note, auto, lanes_note, pilot)


__all__ = ["Resolved", "resolve", "pin_auto_values", "choose_integrator", "job_integrator_values",
           "lanes_for", "budget_request", "object_children", "with_inner", "with_firefly"]
