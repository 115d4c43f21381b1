"""Resolving a `Job`, once: the scene loaded, its own integrator settings merged, `auto`
values pinned, the sample budget split.

    r = resolve(Job(scene="scene.xml", given={"style": "cel"}, samples=64))
    r.scene, r.integrator, r.spp, r.lanes, r.auto   # what `execute` runs; auto: the values pinned
    r.budget                                        # the split: spp x children (`budget.Split`)

The integrator is a prebuilt one as it is; else the given values laid over the scene's own
`stylized` integrator (also one nested in `moment` or `aov`); else over the scene's carried
settings (`carried`) with the job's default style. The job's samples (else the scene's sample
count) are split into camera samples and children once, here, by `budget.split`: a count the
budget chooses replaces the integrator's default (`with_inner`; a count given, by the caller or the
scene file, is kept). Its `auto` values are then pinned on this scene
(`scene.defaults.resolve_defaults`), so every route that renders the result draws the same image.
Design: docs/design/render_pipeline.md.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from styletrace.config import settings as S
from styletrace.gate import mi
from styletrace.kernel.integrator import StylizedIntegrator
from styletrace.pipeline.budget import Request, Split, split
from styletrace.pipeline.carried import carried_settings, nested_stylized
from styletrace.pipeline.job import Job
from styletrace.pipeline.passes import pin_auto_values
from styletrace.pipeline.sizing import lanes_per_pass
from styletrace.scene.arguments import SPP_MAX, check_render_args, whole
from styletrace.scene.defaults import ScenePilot
from styletrace.scene.loading import load_scene, scene_spp
from styletrace.scene.plugins import init


@dataclass(frozen=True)
class Resolved:
    """A job with its scene loaded and its integrator final: everything `execute` needs."""
    job: Job
    scene: mi.Scene
    integrator: mi.Integrator
    spp: int
    lanes: int
    auto: str = ""        # the auto values pinned, one line ('' if none)
    lanes_note: str | None = None  # why the device's pass size is below its default, if it is
    # the scene-defaults pilot the auto values came from (the recorder stores it)
    pilot: ScenePilot | None = None
    budget: Split | None = None  # the samples split into spp x children (`budget.split`)

    @property
    def size(self) -> tuple[int, int]:
        size = self.scene.sensors()[0].film().crop_size()
        return int(size[0]), int(size[1])


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


def budget_request(job: Job, integrator: mi.Integrator, samples: int) -> Request:
    """What the job and its integrator say about the render's cost (`budget.Request`).

    Args:
        job: the job (its spp, and whether it names samples).
        integrator: the job's integrator before its auto values are pinned.
        samples: the budget: the job's samples, else the scene's sample count.

    Returns:
        The request. The children count as given where the integrator's values name
        `inner_samples` (the caller's, the scene file's own `stylized`), and for a prebuilt
        integrator of another class; an integrator without styles draws no children. With error
        AOVs an auto spp is at least 2 (their variance; `runner.Runner.check`).
    """
    given = job.samples is not None
    least = 2 if integrator.aov_names() else 1
    if not isinstance(integrator, StylizedIntegrator):
        return Request(samples, job.spp, None, 0, samples_given=given, min_spp=least)
    s = integrator.settings
    fixed = "inner_samples" in integrator.values or type(integrator) is not StylizedIntegrator
    return Request(samples, job.spp, s.slot.inner if fixed else None, s.slot.style.default_inner,
                   s.stylize_depth, given, least)


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


def resolve(job: Job, scene: mi.Scene | None = None) -> Resolved:
    """Resolve a job once: load its scene, choose its integrator, pin its `auto` values.

    Args:
        job: the job to resolve.
        scene: the scene already loaded from `job.scene` (None: loaded here).

    Returns:
        The `Resolved` job: scene, integrator (auto values pinned), spp, lanes, the line naming the
        auto values (the split first), the lanes note, the scene-defaults pilot and the split.

    Raises:
        UsageError: a bad spp, samples, seed or integrator (`scene.arguments.check_render_args`),
            or samples, spp and inner that disagree (`budget.split`).
    """
    check_render_args(1 if job.spp is None else job.spp, job.seed, job.integrator)
    if job.samples is not None:
        whole("samples", job.samples, 1, SPP_MAX)
    if scene is None:
        scene = load_scene(job.scene, job.width, job.height, dict(job.defines) or None)
    chosen = choose_integrator(scene, job)
    samples = scene_spp(scene) if job.samples is None else int(job.samples)
    budget = split(budget_request(job, chosen, samples))
    if isinstance(chosen, StylizedIntegrator):
        chosen = with_inner(chosen, budget.inner)
    # one pilot for the auto values and, with --buffer, the recorder (it traces only if a value
    # needs it)
    pilot = ScenePilot(scene, chosen.settings) if isinstance(chosen, StylizedIntegrator) else None
    integrator, auto = pin_auto_values(scene, chosen, pilot)
    auto = "; ".join(a for a in (budget.note, auto) if a)
    lanes, note = lanes_for(job)
    return Resolved(job, scene, integrator, budget.spp, lanes, auto, note, pilot, budget)


__all__ = ["Resolved", "resolve", "pin_auto_values", "choose_integrator", "job_integrator_values",
           "lanes_for", "budget_request", "with_inner"]
