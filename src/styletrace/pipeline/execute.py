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
    """What every Ray task of this render receives (`pipeline.ray_tasks.RayJob`); `camera`: the
    sensor's to_world (4x4) in place of the scene's (a frame of a turntable), or None."""
    from styletrace.pipeline.ray_run import job_for
    job = resolved.job
    load = {"defines": dict(job.defines)} if job.defines else {}
    return job_for(job.scene, resolved.integrator, job.width, job.height, camera, **load)


class InProcess:
    """The passes in this process (`passes.passes`: tiles, pass seeds, the float32 sum)."""
    local = True

    def source(self, resolved: Resolved,
               lock: Any = contextlib.nullcontext()) -> Iterator[Progress]:
        """The render's passes, the running average after each; `lock` is held while the sum
        changes."""
        job = resolved.job
        return passes(resolved.scene, resolved.integrator, resolved.spp, job.seed,
                      lanes_per_pass=resolved.lanes, pass_spp=job.pass_spp, lock=lock, pinned=True)


class OnRay:
    """The passes as Ray tasks on `cluster` ("local" or an address); `camera`: the sensor's to_world
    (4x4) on the workers in place of the scene's (a frame of a turntable), or None; `options`:
    output, resume and checkpoint_every of `pipeline.ray_run.Render`. The source also has `save()`
    and `finish()`."""
    local = False

    def __init__(self, cluster: str | None = None, camera: Any = None, **options: Any):
        self.cluster, self.camera, self.options = cluster or "local", camera, options

    def source(self, resolved: Resolved, lock: Any = contextlib.nullcontext()):
        from styletrace.pipeline.ray_run import Render
        job = resolved.job
        width, height = resolved.size
        return Render(ray_job(resolved, self.camera), resolved.spp, job.seed, width, height,
                      self.cluster, resolved.lanes, job.pass_spp, lock=lock, **self.options)


def executor_for(cluster: str | None = None, **ray_options: Any):
    """InProcess, or OnRay where a cluster is named or a checkpoint is to be resumed."""
    if cluster is None and not ray_options.get("resume"):
        return InProcess()
    return OnRay(cluster, **ray_options)


def execute(resolved: Resolved, cluster: str | None = None, lock: Any = contextlib.nullcontext(),
            **ray_options: Any) -> Iterator[Progress]:
    """The render's passes through a plain `runner.Runner` (its checks first): in process, or on Ray
    with `cluster` (`ray_options` as `OnRay`'s)."""
    from styletrace.pipeline.runner import Runner
    return Runner(resolved, executor_for(cluster, **ray_options)).passes(lock)


def run_resolved(resolved: Resolved, cluster: str | None = None,
        callback: Callable[[Progress], None] | None = None):
    """The final image (float32 H x W x C), or (image, aovs) for an integrator with aovs=True."""
    from styletrace.pipeline.runner import Runner
    return Runner(resolved, executor_for(cluster)).result(callback)


def render_pipeline(scene: Any = None, style: str | None = None, spp: int | None = None,
                    inner: Any = None,
           estimator: str | None = None, seed: int = 0, width: int | None = None,
           height: int | None = None, integrator: Any = None,
           callback: Callable[[Progress], None] | None = None, cluster: str | None = None,
           pass_spp: int | None = None, defines: dict[str, Any] | None = None,
           **params: Any) -> np.ndarray:
    """`styletrace.render`: float32 H x W x C, linear radiance in the film's pixel format (C = 3 for
    the usual rgb film); with `aovs=True` `(image, aovs)` (`Progress.aovs`).

    `scene`: built-in name, XML path, scene dict or mi.Scene; `defines`: the XML file's `<default>`
    parameters. `spp`: camera samples per pixel (default: the scene sampler's sample_count). The
    style, `inner`, `estimator`, integrator properties and the style's parameters (**params) refine
    the scene's own `stylized` integrator, else the max_depth, rr_depth and hide_emitters of its
    Mitsuba integrator (through `moment`/`aov` wrappers) with the identity style; `auto` values are
    resolved on the scene. `integrator=` renders with a prebuilt one as it is. `cluster` ("local" or
    a Ray address) renders the passes on Ray, bit-identical to the same split here; `pass_spp` fixes
    the split (default: by the device's memory)."""
    job = python_job(scene, style, spp, inner, estimator, seed, width, height, integrator, defines,
                     pass_spp, **params)
    return run_resolved(resolve(job), cluster, callback)


__all__ = ["InProcess", "OnRay", "executor_for", "execute", "run_resolved", "render_pipeline",
           "ray_job"]
