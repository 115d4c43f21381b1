"""What Ray workers run: one (tile, pass) unit, or one whole frame.

    ref = render_unit.options(num_cpus=1, max_retries=3).remote(job, unit, tile)   # -> (float32 tile, pid)

A worker is a long-lived process: `describe.load` keeps the scene and the integrator it built, so only a
worker's first task loads anything. Each task first sets Dr.Jit's thread count to the CPUs Ray assigned
to it (`num_cpus` of the task), so several workers on one machine do not oversubscribe its cores.
"""
from __future__ import annotations

import os
from dataclasses import dataclass

import ray

from styletrace.jit import no_collection
from styletrace.pipeline.ray_describe import SceneSpec, load


@dataclass(frozen=True)
class Job:
    """What every task of a render shares: the scene, the integrator's property values, the variant."""
    spec: SceneSpec
    values: dict
    variant: str


def _threads() -> int:
    cpus = ray.get_runtime_context().get_assigned_resources().get("CPU", 1)
    return max(1, int(round(cpus)))


def _prepare(job: Job):
    import drjit as dr
    scene, integrator = load(job.spec, job.values, job.variant)
    dr.set_thread_count(_threads())
    return scene, integrator


@ray.remote
def render_unit(job: Job, spp: int, seed: int, offset: tuple[int, int], size: tuple[int, int]):
    """Render the crop window (`offset`, `size`, relative to the film's own crop) with `spp` samples and
    `seed`; returns the float32 window and this worker's process id."""
    import mitsuba as mi
    import numpy as np

    from styletrace.pipeline.passes import Crop
    scene, integrator = _prepare(job)
    with Crop(scene.sensors()[0]) as crop:
        if tuple(size) != crop.full:  # as the pass loop does for its tiles
            crop.set(offset, size)
        with no_collection():  # as the pass loop: no scene finalised while the pass is recorded
            img = mi.render(scene, integrator=integrator, spp=spp, seed=seed)
            arr = np.array(img, dtype=np.float32)[..., :3]
    return arr, os.getpid()


@ray.remote
def render_frame(job: Job, to_world, spp: int, seed: int, lanes_per_pass: int, pass_spp: int | None):
    """One whole frame with `api.passes` (the sensor's to_world replaced by the 4x4 `to_world`, if given);
    returns the float32 image and this worker's process id."""
    import mitsuba as mi
    import numpy as np

    from styletrace.pipeline import passes as pass_loop
    scene, integrator = _prepare(job)
    params = mi.traverse(scene.sensors()[0]) if to_world is not None else None
    old = None
    try:
        if params is not None:
            old = mi.ScalarTransform4f(np.array(scene.sensors()[0].world_transform().matrix, dtype=np.float64)
                                       .reshape(4, 4, -1)[..., 0])
            params["to_world"] = mi.ScalarTransform4f(np.asarray(to_world, dtype=np.float64))
            params.update()
        image = None
        for prog in pass_loop.passes(scene, integrator, spp, seed, lanes_per_pass=lanes_per_pass, pass_spp=pass_spp,
                                     pinned=True):
            image = prog.image
    finally:
        if old is not None:
            params["to_world"] = old
            params.update()
    return image, os.getpid()


__all__ = ["Job", "render_unit", "render_frame"]
