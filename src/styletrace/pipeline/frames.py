"""Frames as Ray tasks: a turntable of one scene (`--frames N --orbit DEGREES`) or a list of XML files.

    paths = render_frames(jobs_and_cameras, spp, seed, output, cluster)   # out_0000.png, out_0001.png, ...

One task renders one whole frame with `api.passes` on its worker (memory flat as in a local render) and
returns the image; the driver writes each as it arrives (atomically) and records it in a manifest
(`OUT.frames.json`), so `--resume` renders only the frames not yet written. Every frame uses the render's
seed: the noise pattern stays put from frame to frame instead of flickering. Ctrl-C cancels the frames
under way; the written ones stay.
"""
from __future__ import annotations

import json
from typing import Any, Callable

from styletrace.errors import UsageError
from styletrace.images import save_safely, write_bytes_atomically
from styletrace.pipeline.ray_cluster import connect, cpus
from styletrace.pipeline.ray_run import MAX_RETRIES, _result


class Manifest:
    """Which frames of OUT are written, for the render's settings."""

    def __init__(self, output: str, settings: dict):
        self.path = output + ".frames.json"
        self.settings = json.loads(json.dumps(settings, sort_keys=True, default=repr))
        self.done: set[int] = set()

    def load(self) -> set[int]:
        try:
            with open(self.path) as f:
                body = json.load(f)
        except FileNotFoundError:
            raise UsageError(f"cannot resume: no frames manifest {self.path!r}") from None
        except (OSError, ValueError) as exc:
            raise UsageError(f"cannot resume: unreadable frames manifest {self.path!r} ({exc})") from None
        if body.get("settings") != self.settings:
            raise UsageError(f"cannot resume {self.path!r}: its frames were rendered with other settings; drop "
                             f"--resume to start over")
        self.done = set(body.get("done", []))
        return self.done

    def add(self, frame: int) -> None:
        self.done.add(frame)
        body = {"settings": self.settings, "done": sorted(self.done)}
        write_bytes_atomically(json.dumps(body, indent=1, sort_keys=True).encode(), self.path)


def render_frames(frames: list[tuple[Any, Any]], paths: list[str], spp: int, seed: int, cluster: str,
                  lanes_per_pass: int, pass_spp: int | None, manifest: Manifest, resume: bool = False,
                  on_frame: Callable[[int, str], None] | None = None) -> list[int]:
    """Render `frames` (job, to_world or None) into `paths`; returns the frames written by this call."""
    ray = connect(cluster)
    from styletrace.pipeline.ray_tasks import render_frame
    skip = manifest.load() if resume else set()
    todo = [i for i in range(len(frames)) if i not in skip]
    todo.reverse()
    task = render_frame.options(num_cpus=1, max_retries=MAX_RETRIES)
    window = max(2, 2 * cpus())
    refs: dict[Any, Any] = {}
    jobs: dict[int, Any] = {}
    written = []
    try:
        while todo or refs:
            while todo and len(refs) < window:
                i = todo.pop()
                job, to_world = frames[i]
                if id(job) not in jobs:
                    jobs[id(job)] = ray.put(job)
                m = None if to_world is None else to_world.tolist()
                refs[task.remote(jobs[id(job)], m, spp, seed, lanes_per_pass, pass_spp)] = i
            done, _ = ray.wait(list(refs), num_returns=1)
            for ref in done:
                i = refs.pop(ref)
                image, _pid = _result(ray, ref)
                out = save_safely(image.copy(), paths[i])  # Ray hands out read-only arrays; Mitsuba needs writable
                if out == paths[i]:
                    manifest.add(i)
                written.append(i)
                if on_frame is not None:
                    on_frame(i, out)
    finally:
        for ref in refs:
            ray.cancel(ref)
    return written


def frame_settings(kind: str, scenes: list, values: list, spp: int, seed: int, count: int, orbit: float | None,
                   lanes: int, pass_spp: int | None, variant: str) -> dict:
    return {"kind": kind, "scenes": scenes, "integrators": values, "spp": spp, "seed": seed, "frames": count,
            "orbit": orbit, "lanes_per_pass": lanes, "pass_spp": pass_spp, "variant": variant}


__all__ = ["render_frames", "Manifest", "frame_settings"]
