"""Frames on Ray: each chunk of frames one task, each frame streamed back as it is written.

    written, status = render_frames_on_ray(chunks, paths, manifest, "local", on_frame=...)

A chunk (`animation.frame_chunks.Chunk`) runs in a worker exactly as it runs in this process
(`ray_chunk_task.render_chunk_task`: the runner in process, the finisher of its method, the chunk's
history), so a frame is the same bit for bit wherever it rendered. The task is a Ray streaming
generator: each frame's file comes back as soon as the worker wrote it, and this process writes it
atomically to its numbered path and records it in the manifest. At most as many chunks run at once
as the cluster has CPUs, one CPU each (a worker sets Dr.Jit's threads to it). A styletrace error in
a task is raised here as itself; Ctrl-C (or any error) cancels the chunks under way, and the frames
written stay for `--resume`. Design: docs/design/ray_rendering.md.
"""
from __future__ import annotations

import os
from typing import Callable

from styletrace.animation.frame_chunks import FrameStopped
from styletrace.images import write_bytes_atomically
from styletrace.pipeline.ray_cluster import connect, cpus
from styletrace.pipeline.ray_run import MAX_RETRIES, task_result


def render_frames_on_ray(chunks: list, paths: list[str], manifest, cluster: str,
                         resume: bool = False,
                         on_frame: Callable[[int, str], None] | None = None,
                         cpus_per_task: int = 1) -> tuple[list[int], int, set[int]]:
    """Render the chunks as Ray tasks, writing each frame as it arrives (module doc).

    Args:
        chunks: the `frame_chunks.Chunk`s. paths: every frame's image. manifest: the written
            frames' `frames.Manifest`. cluster: "local" or a Ray address.
        resume: skip the frames the manifest names (a chunk they all fill is not sent).
        on_frame: called with (frame, path) after each frame is written. cpus_per_task: a task's
            CPUs (its Dr.Jit threads).

    Returns:
        (the frames written by this call, in the order they came; 0 or the exit status of a frame
        that stopped; the process ids of the workers that rendered them).

    Raises:
        StyletraceError: a task's refusal, as itself (one line). RuntimeError: a task that failed
            otherwise. KeyboardInterrupt: Ctrl-C; the chunks under way are cancelled.
    """
    skip = manifest.load() if resume else set()
    todo = [c for c in chunks if any(i not in skip for i in c.indices)]
    if not todo:
        return [], 0, set()
    ray = connect(cluster)
    from styletrace.animation.ray_chunk_task import render_chunk_task
    task = render_chunk_task.options(num_cpus=cpus_per_task, num_returns="streaming",
                                     max_retries=MAX_RETRIES)
    window = max(1, cpus() // max(1, cpus_per_task))
    ext = os.path.splitext(paths[0])[1]
    written: list[int] = []
    pids: set[int] = set()
    running: list = []
    todo.reverse()  # pop() from the end takes them in frame order
    try:
        while todo or running:
            while todo and len(running) < window:
                chunk = todo.pop()
                done = frozenset(i for i in chunk.indices if i in skip)
                running.append(task.remote(chunk, ext, done))
            ready, _ = ray.wait(running, num_returns=1)
            for gen in ready:
                try:
                    ref = next(gen)
                except StopIteration:  # the chunk is done
                    running.remove(gen)
                    continue
                i, data, pid = task_result(ray, ref)
                pids.add(pid)
                if i in skip or i in written:  # a retried task's frames come again
                    continue
                write_bytes_atomically(data, paths[i])
                manifest.add(i)
                written.append(i)
                if on_frame is not None:
                    on_frame(i, paths[i])
    except FrameStopped as stop:
        return written, stop.status, pids
    finally:
        for gen in running:  # a kernel under way cannot be stopped: its worker is ended
            ray.cancel(gen, force=True)
    return written, 0, pids


__all__ = ["render_frames_on_ray"]
