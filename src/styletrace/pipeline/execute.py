"""Where the passes of a resolved render run: in this process (tiled), or as Ray tasks; `render`.

    source = InProcess().source(resolve(job))             # a passes.Progress after each pass
    source = OnRay("local", output="o.exr").source(resolve(job), lock)   # the same, as Ray tasks
    image = render("scene.xml", style="cel", defines={"depth": "3"}, cluster="local")

In process the passes are `passes.passes`; on Ray the same launches, with the same seeds and the
same float32 merge, are Ray tasks (`pipeline.ray_run.Render`), so the image is bit-identical for the
same seed and split. Ray workers receive the job's scene source and the resolved integrator's
property values (auto values pinned), never the loaded objects. A `runner.Runner` drives either (the
executor of every front end).
"""
from __future__ import annotations

import contextlib
from typing import Any, Callable, Iterator

import numpy as np

from styletrace.pipeline.job import python_job
from styletrace.pipeline.passes import Progress, passes
from styletrace.pipeline.resolve import Resolved, resolve


def ray_job(resolved: Resolved, camera: Any = None):
    """What every Ray task of this render receives (`pipeline.ray_tasks.RayJob`).

    Args:
        resolved: the resolved job; its scene source, defines, size and integrator values travel.
        camera: the sensor's to_world (4x4) in place of the scene's (a turntable's frame), or None.


    Returns:
        The RayJob.

    Raises:
        UsageError: a scene or an integrator that cannot travel (`pipeline.ray_run.job_for`).
    """
    from styletrace.pipeline.ray_run import job_for
    job = resolved.job
    load = {"defines": dict(job.defines)} if job.defines else {}
    return job_for(job.scene, resolved.integrator, job.width, job.height, camera, **load)


class InProcess:
    """The passes in this process (`passes.passes`: tiles, pass seeds, the float32 sum)."""
    local = True

    def source(self, resolved: Resolved, lock: Any = contextlib.nullcontext(),
               in_pixels: bool = False) -> Iterator[Progress]:
        """The render's passes in this process (`passes.passes`, the `auto` values pinned already).

        Args:
            resolved: the resolved job.
            lock: a context manager held while the running sum changes.
            in_pixels: each sample kept in its own pixel (the image denoiser's: `passes.passes`).

        Returns:
            An iterator of `Progress`, the running average after each pass.
        """
        job = resolved.job
        return passes(resolved.scene, resolved.integrator, resolved.spp, job.seed,
                      lanes_per_pass=resolved.lanes, pass_spp=job.pass_spp, lock=lock, pinned=True,
                      in_pixels=in_pixels)


class OnRay:
    """The passes as Ray tasks; the source also has `save()` and `finish()`.

    Args:
        cluster: "local" or a Ray address (None: "local").
        camera: the sensor's to_world (4x4) on the workers in place of the scene's (a frame of a
            turntable), or None.
        **options: output, resume and checkpoint_every of `pipeline.ray_run.Render`.
    """
    local = False

    def __init__(self, cluster: str | None = None, camera: Any = None, **options: Any):
        self.cluster, self.camera, self.options = cluster or "local", camera, options

    def source(self, resolved: Resolved, lock: Any = contextlib.nullcontext()):
        """The render's passes as Ray tasks (`pipeline.ray_run.Render`).

        Args:
            resolved: the resolved job. lock: held while the merged sum changes.

        Returns:
            The Render: an iterable of `Progress`, with `save()` and `finish()`.

        Raises:
            UsageError: a job that cannot run on Ray (an expansion pass, a scene or integrator that
                cannot travel, an unfinished checkpoint without resume).
        """
        from styletrace.pipeline.ray_run import Render
        job = resolved.job
        width, height = resolved.size
        return Render(ray_job(resolved, self.camera), resolved.spp, job.seed, width, height,
                      self.cluster, resolved.lanes, job.pass_spp, lock=lock, **self.options)


def executor_for(cluster: str | None = None, **ray_options: Any):
    """The executor of a run: in this process, or on Ray.

    Args:
        cluster: "local" or a Ray address; None renders in process unless resuming.
        **ray_options: output, resume and checkpoint_every (`OnRay`).

    Returns:
        InProcess, or OnRay where a cluster is named or `resume` is set.
    """
    if cluster is None and not ray_options.get("resume"):
        return InProcess()
    return OnRay(cluster, **ray_options)


def execute(resolved: Resolved, cluster: str | None = None, lock: Any = contextlib.nullcontext(),
            **ray_options: Any) -> Iterator[Progress]:
    """The render's passes through a plain `runner.Runner` (its checks first).

    Args:
        resolved: the resolved job. cluster: as `executor_for`'s (None: in process).
        lock: held while the running sum changes. **ray_options: as `OnRay`'s.

    Returns:
        An iterator of `Progress`, one after each pass.

    Raises:
        UsageError: a refusal of the runner's checks (one line).
    """
    from styletrace.pipeline.runner import Runner
    return Runner(resolved, executor_for(cluster, **ray_options)).passes(lock)


def run_resolved(resolved: Resolved, cluster: str | None = None,
        callback: Callable[[Progress], None] | None = None):
    """Render a resolved job to its final result through a plain `runner.Runner`.

    Args:
        resolved: the resolved job. cluster: "local" or a Ray address (None: in process).
        callback: called with the `Progress` after each pass, or None.

    Returns:
        The image (float32 H x W x C), or (image, aovs) for an integrator with aovs=True.

    Raises:
        UsageError: a refusal of the runner's checks (one line).
    """
    from styletrace.pipeline.runner import Runner
    return Runner(resolved, executor_for(cluster)).result(callback)


def render_pipeline(scene: Any = None, style: str | None = None, spp: int | None = None,
                    inner: Any = None,
           estimator: str | None = None, seed: int = 0, width: int | None = None,
           height: int | None = None, integrator: Any = None,
           callback: Callable[[Progress], None] | None = None, cluster: str | None = None,
           pass_spp: int | None = None, defines: dict[str, Any] | None = None,
           samples: int | None = None, **params: Any) -> np.ndarray:
    """`styletrace.render`: a Job of the keywords (`job.python_job`), resolved once, run in passes.

    Args:
        scene, spp, seed, width, height, integrator, defines, pass_spp: as `job.Job`'s fields.
        samples: paths per pixel, whatever the style (None: the scene's sample count), split into
            spp x children (`pipeline.budget`); spp and inner, where given, win.
        style, inner, estimator, **params: the integrator values given (`job.Job`'s `given`);
            `auto` values are resolved on the scene.
        callback: called with each pass's `Progress`. cluster: "local" or a Ray address: the passes
            on Ray, bit-identical to the same split in process (None: in process).

    Returns:
        float32 H x W x C, linear radiance in the film's pixel format (C = 3 for the usual rgb
        film); with aovs=True, (image, aovs) (`Progress.aovs`).
    """
    job = python_job(scene, style, spp, inner, estimator, seed, width, height, integrator, defines,
                     pass_spp, samples, **params)
    return run_resolved(resolve(job), cluster, callback)


__all__ = ["InProcess", "OnRay", "executor_for", "execute", "run_resolved", "render_pipeline",
           "ray_job"]
