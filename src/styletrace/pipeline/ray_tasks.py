"""What Ray workers run: one (tile, pass) unit of a render, or one chunk of frames.

    ref = render_unit.options(num_cpus=1, max_retries=3).remote(job, spp, seed, offset, size,
                                                                 sequence)
    gen = render_chunk_task.options(num_cpus=1, num_returns="streaming").remote(chunk, ".exr", skip)
    for ref in gen: frame, data, pid = ray.get(ref)     # each frame's file as it is written

A worker is a long-lived process: `ray_describe.load_on_worker` keeps the scene and the integrator
it built, so only a worker's first task loads anything. Each task first sets Dr.Jit's thread count
to the CPUs Ray assigned to it (`num_cpus` of the task), so several workers on one machine do not
oversubscribe its cores (a chunk of frames at least 2: `render_chunk_task`). A job's `camera` (a
frame of a turntable) replaces the sensor's to_world while the unit renders. A chunk of frames
runs the pipeline a frame runs in the driver's process (`frame_chunks.render_chunk`), into a
temporary folder of its own, and streams each written file back as it comes.
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


def _threads() -> int:
    cpus = ray.get_runtime_context().get_assigned_resources().get("CPU", 1)
    return max(1, int(round(cpus)))


def _prepare(job: RayJob):
    scene, integrator = load_on_worker(job.spec, job.values, job.variant)
    from styletrace.gate import dr  # deliberately here: after `load` chose the driver's variant
    dr.set_thread_count(_threads())
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


@ray.remote
def render_chunk_task(chunk, ext: str, skip: frozenset = frozenset()):
    """Render a chunk of frames in a worker, as this process would (`frame_chunks.render_chunk`),
    each into a temporary folder of the task's own; a streaming generator.

    Args:
        chunk: the `frame_chunks.Chunk`. ext: the images' extension (".exr", ".png": the format).
        skip: the chunk's frames written already (rendered only where the history needs them).

    Returns:
        An iterator of (frame index, the written file's bytes, this worker's process id), one as
        each frame is written.

    Raises:
        StyletraceError: a refusal of a frame's run, or `frame_chunks.FrameStopped`.
    """
    import tempfile

    from styletrace.pipeline.frame_chunks import render_chunk
    from styletrace.scene import plugins
    plugins.init(chunk.frames[0].scene.variant)
    from styletrace.gate import dr  # deliberately here: after `init` chose the driver's variant
    # at least 2: Mitsuba's OpenEXR writer never returns with a pool of one thread (measured with
    # Mitsuba 3, a 16 x 16 image; the image is the same at any thread count)
    dr.set_thread_count(max(2, _threads()))
    with tempfile.TemporaryDirectory(prefix="styletrace-frames-") as folder:
        paths = {i: os.path.join(folder, f"frame_{i:04d}{ext}") for i in chunk.indices}
        for i, path in render_chunk(chunk, paths, skip):
            with open(path, "rb") as f:
                data = f.read()
            os.remove(path)
            yield i, data, os.getpid()


__all__ = ["RayJob", "render_unit", "render_chunk_task"]
