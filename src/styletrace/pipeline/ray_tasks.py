"""What Ray workers run: one (tile, pass) unit of a render (a chunk of frames:
`animation.ray_chunk_task`).

    ref = render_unit.options(num_cpus=1, max_retries=3).remote(job, spp, seed, offset, size,
                                                                 sequence)

A worker is a long-lived process: `ray_describe.load_on_worker` keeps the scene and the integrator
it built, so only a worker's first task loads anything. Each task first sets Dr.Jit's thread count
to the CPUs Ray assigned to it (`num_cpus` of the task), so several workers on one machine do not
oversubscribe its cores (`assigned_threads`). A job's `camera` (a frame of a turntable) replaces
the sensor's to_world while the unit renders.
"""
from __future__ import annotations

import os
from dataclasses import dataclass

import numpy as np
import ray

from styletrace.jit import no_collection
from styletrace.pipeline.ray_describe import SceneSpec, load_on_worker


@dataclass(frozen=True)
class RayJob:
    """What every task of a render shares: the scene, the integrator's property values, the variant
    and the camera (the sensor's to_world as 4 rows of 4, or None for the scene's own)."""
    spec: SceneSpec
    values: dict
    variant: str
    camera: tuple | None = None


def assigned_threads() -> int:
    """The CPUs Ray assigned to the task under way (its `num_cpus`), at least 1: the Dr.Jit
    threads it may use."""
    cpus = ray.get_runtime_context().get_assigned_resources().get("CPU", 1)
    return max(1, int(round(cpus)))


def _prepare(job: RayJob):
    scene, integrator = load_on_worker(job.spec, job.values, job.variant)
    from styletrace.gate import dr  # deliberately here: after `load` chose the driver's variant
    dr.set_thread_count(assigned_threads())
    return scene, integrator


@ray.remote
def render_unit(job: RayJob, spp: int, seed: int, offset: tuple[int, int], size: tuple[int, int],
                sequence=None):
    """Render one unit's crop window in a worker.

    Args:
        job: the render's `RayJob`. spp: camera samples per pixel. seed: the unit's seed.
        offset, size: the crop window, relative to the film's own crop, in pixels.
        sequence: the unit's place in the render's sequence (`passes.unit_sequence`; None: its
            own).

    Returns:
        (the float32 window, h x w x 3; this worker's process id).
    """
    scene, integrator = _prepare(job)
    # deliberately here: after `load` chose the driver's variant
    from styletrace.kernel.data_passes import placed
    from styletrace.kernel.launch import render_pass
    from styletrace.pipeline.passes import Crop
    sensor = scene.sensors()[0]
    with placed(sensor, job.camera), Crop(sensor) as crop:
        if tuple(size) != crop.full:  # as the pass loop does for its tiles
            crop.set(offset, size)
        with no_collection():  # as the pass loop: no scene finalised while the pass is recorded
            img = render_pass(scene, integrator, spp, seed, sequence)
            arr = np.array(img, dtype=np.float32)[..., :3]
    return arr, os.getpid()


__all__ = ["RayJob", "render_unit", "assigned_threads"]
