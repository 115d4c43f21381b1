"""What a Ray worker runs for a chunk of frames: the pipeline a frame runs in the driver's process
(`frame_chunks.render_chunk`), into a temporary folder of its own, each written file streamed
back as it comes.

    gen = render_chunk_task.options(num_cpus=1, num_returns="streaming").remote(chunk, ".exr", skip)
    for ref in gen: frame, data, pid = ray.get(ref)     # each frame's file as it is written

Dr.Jit's threads: the CPUs Ray assigned (`pipeline.ray_tasks.assigned_threads`), at least 2.
"""
from __future__ import annotations

import os

import ray

from styletrace.pipeline.ray_tasks import assigned_threads


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

    from styletrace.animation.frame_chunks import render_chunk
    from styletrace.scene import plugins
    plugins.init(chunk.frames[0].scene.variant)
    from styletrace.gate import dr  # deliberately here: after `init` chose the driver's variant
    # at least 2: Mitsuba's OpenEXR writer never returns with a pool of one thread (measured with
    # Mitsuba 3, a 16 x 16 image; the image is the same at any thread count)
    dr.set_thread_count(max(2, assigned_threads()))
    with tempfile.TemporaryDirectory(prefix="styletrace-frames-") as folder:
        paths = {i: os.path.join(folder, f"frame_{i:04d}{ext}") for i in chunk.indices}
        for i, path in render_chunk(chunk, paths, skip):
            with open(path, "rb") as f:
                data = f.read()
            os.remove(path)
            yield i, data, os.getpid()


__all__ = ["render_chunk_task"]
