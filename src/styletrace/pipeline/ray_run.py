"""The driver of a render on Ray: hand out (tile, pass) units, merge them, checkpoint, report
progress.

    run = Render(job, Plan(512, 512, spp=256, seed=0), "local", Checkpoints(output="o.exr"))
    for prog in run: ...   # a pipeline.passes.Progress after each finished unit

Units go out in launch order, at most twice as many as the cluster runs at once. A task whose
worker dies runs again (`MAX_RETRIES`); a styletrace error in a task is raised here as itself.
Breaking out of the loop cancels the units under way and checkpoints the finished ones; checkpoints
come at most every `Checkpoints.every` seconds and change nothing in the image.
Design: docs/design/ray_rendering.md.
"""
from __future__ import annotations

import contextlib
import time
from typing import Any, Callable, Iterator

import numpy as np

from styletrace.errors import StyletraceError, UsageError
from styletrace.pipeline import passes as pass_loop
from styletrace.pipeline.passes import Progress
from styletrace.pipeline.ray_checkpoint import Checkpoint, Checkpoints
from styletrace.pipeline.ray_cluster import connect, cpus
from styletrace.pipeline.ray_describe import SceneSpec
from styletrace.pipeline.ray_plan import Merge, Plan, plan_units
from styletrace.scene.loading import first_line

#: Retries of a task whose worker process died (Ray re-runs it elsewhere; the unit's seed is fixed).
MAX_RETRIES = 3


def settings_of(job, plan: Plan) -> dict:
    """What a checkpoint must match to be resumed.

    Args:
        job: the `ray_tasks.RayJob`. plan: the film's size, spp, seed and pass split.

    Returns:
        The settings: scene, integrator values, sampling, size, split (camera samples per pass,
        camera samples per pixel of a pass, tile count), variant, and the camera of a turntable's
        frame.
    """
    layout, per_pass = plan.split.size(plan.width, plan.height, plan.spp)
    settings = {"scene": job.spec.describe(), "integrator": job.values, "spp": plan.spp,
                "seed": plan.seed, "size": [plan.width, plan.height],
                "lanes_per_pass": plan.split.lanes_per_pass, "pass_spp": per_pass,
                "tiles": len(layout), "variant": job.variant}
    if job.camera is not None:  # a frame of a turntable
        settings["camera"] = [list(row) for row in job.camera]
    return settings


class Render:
    """Iterating renders; `progress()` after the loop: the final state; `worker_pids`: who rendered.

    Args:
        job: the `ray_tasks.RayJob`. plan: the film's size, spp, seed and pass split.
        cluster: "local" or a Ray address. checkpoints: whether, where and how often to checkpoint.
        lock: held while the sum changes. cpus_per_task, gpus_per_task: a task's Ray resources.

    Raises:
        UsageError: an expansion pass, an unwritable checkpoint, an unfinished checkpoint without
            `resume`, or a checkpoint that cannot be resumed.
    """

    def __init__(self, job, plan: Plan, cluster: str = "local",
                 checkpoints: Checkpoints = Checkpoints(), lock: Any = contextlib.nullcontext(),
                 cpus_per_task: int = 1, gpus_per_task: float = 0):
        from styletrace.config.settings import parse
        if parse(job.values).expansion_pass:  # a unit is a bare mi.render: no pass map travels
            raise UsageError(f"bad value {job.values['expansion_pass']!r} for 'expansion_pass' in "
                             f"a cluster render: its pre-pass runs in a local render's passes "
                             f"only; render without --ray/cluster=, or use expansion_pass=0")
        self.job, self.spp, self.seed = job, plan.spp, plan.seed
        self.width, self.height = plan.width, plan.height
        self.cluster, self.lock = cluster, lock
        self.layout, self.units = plan_units(plan)
        output = checkpoints.output
        self.checkpoint = None
        if output is not None:
            self.checkpoint = Checkpoint(output, settings_of(job, plan))
        # written beside the output, by the output's rules (images.check_target)
        if self.checkpoint is not None:
            from styletrace.images import check_target
            check_target(self.checkpoint.manifest)
        if self.checkpoint is not None and not checkpoints.resume and self.checkpoint.exists():
            raise UsageError(f"{output!r} has the checkpoint of an unfinished render "
                             f"({self.checkpoint.manifest}): add --resume to continue it, or "
                             f"delete that file to start over")
        total, rounds = self.checkpoint.load() if checkpoints.resume else (None, None)
        self.merge = Merge(plan.width, plan.height, plan.spp, self.layout, total, rounds)
        self.merge.restore_counts(self.units)
        self.resumed_units = sum(rounds) if rounds else 0
        self.checkpoint_every = checkpoints.every
        self.cpus_per_task, self.gpus_per_task = cpus_per_task, gpus_per_task
        self.worker_pids: set[int] = set()
        # called with the worker's pid after each result
        self.on_result: Callable[[int], None] | None = None
        self._last_save = time.monotonic()

    @property
    def total_units(self) -> int:
        return len(self.units)

    def progress(self) -> Progress:
        return self.merge.progress()

    def save(self) -> None:
        """Checkpoint the finished units now (the command line's watcher calls it before it
        abandons)."""
        if self.checkpoint is not None and int(self.merge.counts.min()) < self.spp:
            self.checkpoint.save(self.merge.total, self.merge.rounds_done)
        self._last_save = time.monotonic()

    def finish(self) -> None:
        """The final image is written: the checkpoint has served."""
        if self.checkpoint is not None:
            self.checkpoint.remove()

    def __iter__(self) -> Iterator[Progress]:
        ray = connect(self.cluster)
        from styletrace.pipeline.ray_tasks import render_unit
        todo = [u for u in self.units if u.round >= self.merge.rounds_done[u.tile]]
        todo.reverse()  # pop() from the end takes them in launch order
        window = max(2, 2 * cpus() // max(1, self.cpus_per_task))
        task = render_unit.options(num_cpus=self.cpus_per_task, num_gpus=self.gpus_per_task,
                                   max_retries=MAX_RETRIES)
        job = ray.put(self.job)
        running: dict[Any, Any] = {}
        if self.resumed_units:  # the passes of the checkpoint are the first progress
            yield self.merge.progress()
        try:
            while todo or running:
                while todo and len(running) < window:
                    u = todo.pop()
                    tile = self.layout[u.tile]
                    running[task.remote(job, u.spp, u.seed, tile.offset, tile.size,
                                        pass_loop.unit_sequence(self.seed, u))] = u
                done, _ = ray.wait(list(running), num_returns=1)
                for ref in done:
                    unit = running.pop(ref)
                    arr, pid = task_result(ray, ref)
                    with self.lock:
                        self.merge.add(unit, arr)
                    self.worker_pids.add(pid)
                    if self.on_result is not None:
                        self.on_result(pid)
                    due = time.monotonic() - self._last_save >= self.checkpoint_every
                    if self.checkpoint is not None and due:
                        with self.lock:
                            self.save()
                    yield self.merge.progress()
        finally:
            for ref in running:
                ray.cancel(ref)
            with self.lock:
                self.save()


def task_result(ray, ref) -> tuple[np.ndarray, int]:
    """A task's result; its styletrace error as that error (one line), any other failure as
    RuntimeError."""
    try:
        return ray.get(ref)
    except ray.exceptions.RayTaskError as exc:
        cause = getattr(exc, "cause", None)
        if isinstance(cause, StyletraceError):
            raise cause from None
        raise RuntimeError(f"a Ray task failed: {first_line(cause or exc)}") from None
    except ray.exceptions.RayError as exc:
        raise RuntimeError(f"a Ray task failed: {first_line(exc)}") from None


def job_for(scene: Any, integrator: Any, width: int | None = None, height: int | None = None,
            camera: Any = None, **load_kwargs):
    """The RayJob of a scene and a `stylized` integrator (its values travel, not the object).

    Args:
        scene: a built-in name, an XML path or a scene dict. width, height: the film (None: its).
        integrator: the `stylized` integrator. camera: the sensor's to_world (4x4), or None.
        **load_kwargs: the load's arguments (defines).

    Returns:
        The `ray_tasks.RayJob`, in this process's variant.

    Raises:
        UsageError: an integrator without property values, or a scene that cannot travel.
    """
    from styletrace.pipeline.ray_tasks import RayJob
    from styletrace.scene.plugins import init
    values = getattr(integrator, "values", None)
    if not isinstance(values, dict):
        raise UsageError(f"bad integrator {type(integrator).__name__} for a cluster render: Ray "
                         f"workers rebuild the `stylized` integrator from its property values; "
                         f"pass style= and parameters instead")
    rows = (None if camera is None else
            tuple(tuple(float(v) for v in row) for row in np.asarray(camera)))
    return RayJob(SceneSpec.of(scene, width, height, **load_kwargs), dict(values), init(), rows)


__all__ = ["Render", "job_for", "settings_of", "task_result", "MAX_RETRIES"]
