"""Where the passes of a resolved render run: in this process (tiled), or as Ray tasks.

    source = InProcess().source(resolve(job))             # a passes.Progress after each pass
    source = OnRay("local", checkpoints=Checkpoints("o.exr")).source(resolve(job), lock)  # on Ray
    executor = executor_for(cluster="local")             # what `styletrace.render` runs on

In process the passes are `passes.run_passes`; on Ray the same launches, with the same seeds and the
same float32 merge, are Ray tasks (`pipeline.ray_run.Render`), so the image is bit-identical for the
same seed and split. Ray workers receive the job's scene source and the resolved integrator's
property values (auto values pinned), never the loaded objects. A `runner.Runner` drives either (the
executor of every front end).
"""
from __future__ import annotations

import contextlib
from typing import Any, Iterator

from styletrace.pipeline.passes import PassSplit, Progress, Shot, run_passes
from styletrace.pipeline.ray_checkpoint import Checkpoints
from styletrace.pipeline.resolve import Resolved


def split_of(resolved: Resolved) -> PassSplit:
    """The pass split of a resolved job: its lanes per launch, its job's pass_spp and growth.

    Args:
        resolved: the resolved job.

    Returns:
        The PassSplit.
    """
    return PassSplit(resolved.lanes, resolved.job.pass_spp, resolved.job.pass_growth)


def shot_of(resolved: Resolved) -> Shot:
    """What a resolved job renders: its scene, its integrator (`auto` values pinned), its spp and
    its job's seed.

    Args:
        resolved: the resolved job.

    Returns:
        The Shot.
    """
    return Shot(resolved.scene, resolved.integrator, resolved.spp, resolved.job.seed)


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
    if job.sampler is not None:
        load["sampler"] = job.sampler
    return job_for(job.scene, resolved.integrator, job.width, job.height, camera, **load)


class InProcess:
    """The passes in this process (`passes.run_passes`: tiles, pass seeds, the float32 sum), on the
    scene's own camera (`camera` None)."""
    local = True
    camera = None

    def source(self, resolved: Resolved, lock: Any = contextlib.nullcontext(),
               in_pixels: bool = False) -> Iterator[Progress]:
        """The render's passes in this process (`passes.run_passes`, the `auto` values pinned
        already).

        Args:
            resolved: the resolved job.
            lock: a context manager held while the running sum changes.
            in_pixels: each sample kept in its own pixel (the image denoiser's:
                `passes.run_passes`).

        Returns:
            An iterator of `Progress`, the running average after each pass.
        """
        return run_passes(shot_of(resolved), split_of(resolved), lock, pinned=True,
                          in_pixels=in_pixels)


class OnRay:
    """The passes as Ray tasks; the source also has `save()` and `finish()`.

    Args:
        cluster: "local" or a Ray address (None: "local").
        camera: the sensor's to_world (4x4) on the workers in place of the scene's (a frame of a
            turntable), or None.
        checkpoints: whether, where and how often the render checkpoints
            (`pipeline.ray_checkpoint.Checkpoints`; default: none).
    """
    local = False

    def __init__(self, cluster: str | None = None, camera: Any = None,
                 checkpoints: Checkpoints = Checkpoints()):
        self.cluster, self.camera, self.checkpoints = cluster or "local", camera, checkpoints

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
        from styletrace.pipeline.ray_plan import Plan
        from styletrace.pipeline.ray_run import Render
        width, height = resolved.size
        plan = Plan(width, height, resolved.spp, resolved.job.seed, split_of(resolved))
        return Render(ray_job(resolved, self.camera), plan, self.cluster, self.checkpoints,
                      lock=lock)


def executor_for(cluster: str | None = None, checkpoints: Checkpoints = Checkpoints()):
    """The executor of a run: in this process, or on Ray (the passes of one image; frames run
    in chunks, `animation.frame_chunks`).

    Args:
        cluster: "local" or a Ray address; None renders in process unless resuming.
        checkpoints: a render on Ray's checkpoints (`OnRay`).

    Returns:
        InProcess, or OnRay where a cluster is named or `checkpoints.resume` is set.
    """
    if cluster is None and not checkpoints.resume:
        return InProcess()
    return OnRay(cluster, checkpoints=checkpoints)


__all__ = ["InProcess", "OnRay", "executor_for", "ray_job", "shot_of", "split_of"]
