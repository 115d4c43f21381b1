"""Frames: a turntable of one scene (`--frames N --orbit DEGREES`) or a list of XML files.

    written, status = render_frames(frames, paths, cluster, manifest)   # out_0000.png, ...

Each frame is a run of the render pipeline (`pipeline.runner.Runner`), denoised as a still with
the scene's camera placed at the frame's: in this process, or with its passes as Ray tasks
(`pipeline.execute.OnRay`, with the frame's camera; the driver denoises). The runner owns its pass
loop, its checks, its stop on Ctrl-C or SIGTERM and its atomic write. A frame written to its own
path is recorded in a manifest (`OUT.frames.json`), so `--resume` renders only the frames not yet
written. Every frame uses the render's seed: the noise pattern stays put from frame to frame
instead of flickering. A stop ends the sequence after the frame under way (its finished passes
written, as the runner writes them); the frames recorded stay.
"""
from __future__ import annotations

import json
from typing import Any, Callable

from styletrace.errors import UsageError
from styletrace.images import write_bytes_atomically
from styletrace.kernel.data_passes import placed
from styletrace.pipeline.execute import executor_for
from styletrace.pipeline.resolve import Resolved, resolve
from styletrace.pipeline.runner import Runner, Voice


class Manifest:
    """Which frames of OUT are written, for the render's settings (`OUT.frames.json`).

    Args:
        output: the sequence's output path, OUT.
        settings: the render's settings (`frame_settings`), which a resume must match.
    """

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
            raise UsageError(f"cannot resume: unreadable frames manifest {self.path!r} "
                             f"({exc})") from None
        if body.get("settings") != self.settings:
            raise UsageError(f"cannot resume {self.path!r}: its frames were rendered with other "
                             f"settings; drop --resume to start over")
        self.done = set(body.get("done", []))
        return self.done

    def add(self, frame: int) -> None:
        """Record a frame as written and rewrite the manifest (atomically).

        Args:
            frame: the frame's index.
        """
        self.done.add(frame)
        body = {"settings": self.settings, "done": sorted(self.done)}
        write_bytes_atomically(json.dumps(body, indent=1, sort_keys=True).encode(), self.path)


def render_frames(frames: list[tuple[Any, Any]], paths: list[str], cluster: str | None,
                  manifest: Manifest, resume: bool = False,
                  on_frame: Callable[[int, str], None] | None = None,
                  finisher: Callable[[Resolved], Any] | None = None) -> tuple[list[int], int]:
    """Render each frame through its runner into its path, in order, denoised as the job asks (the
    scene's camera placed at the frame's for the whole run, so that the denoiser's guides and
    points see it too): in this process, or with a cluster, its passes as Ray tasks.

    Args:
        frames: (job, camera) per frame. job: a `Resolved` job, or a `pipeline.job.Job` whose
            integrator is pinned already, resolved when its first frame comes (one scene loaded at a
            time); camera: the sensor's to_world (4x4) or None.
        paths, cluster, manifest: the frames' images, the Ray cluster (None: this process), the
            written frames' manifest.
        resume: skip the frames the manifest names. on_frame: called with (frame, path written).
        finisher: the finisher of a resolved frame (`denoise.finishers.finisher_for`); None:
            the plain one.

    Returns:
        (the frames written by this call, 0 or the exit status of the frame that stopped or failed).
    """
    skip = manifest.load() if resume else set()
    written: list[int] = []
    job, resolved = None, None
    for i, (frame_job, camera) in enumerate(frames):
        if i in skip:
            continue
        if frame_job is not job:
            job = frame_job
            resolved = job if isinstance(job, Resolved) else resolve(job, local=cluster is None)
        executor = executor_for(cluster, camera=camera)
        # the scene's own camera placed at the frame's for the whole run: the passes here, and
        # the denoiser's guides and points (the driver's, for a Ray render) see the frame's
        with placed(resolved.scene.sensors()[0], camera):
            runner = Runner(resolved, executor,
                            finisher(resolved) if finisher is not None else None)
            status = runner.write(paths[i], Voice(quiet=True))
        if runner.written is None:  # stopped, or a pass failed: its finished passes were written
            return written, status
        if runner.written.path == paths[i]:
            manifest.add(i)
        written.append(i)
        if on_frame is not None:
            on_frame(i, runner.written.path)
    return written, 0


def frame_settings(kind: str, scenes: list, values: list, count: int, orbit: float | None,
                   job, variant: str) -> dict:
    """The settings a frames manifest records: what a `--resume` must match.

    Args:
        kind: "orbit" or "files". scenes: the scenes' descriptions. values: their integrator values.
        count, orbit: frames, turn (degrees; None for files).
        job: the frames' `pipeline.job.Job` (any frame's: they share its spp, seed, `samples`
            (the paths per pixel given, or None) and pass split, `lanes_per_pass` set).
        variant: the Mitsuba variant.

    Returns:
        The settings, a dict (`samples` and `passes` only where given: manifests written before
        them resume).
    """
    settings = {"kind": kind, "scenes": scenes, "integrators": values, "spp": job.spp,
                "seed": job.seed, "frames": count, "orbit": orbit,
                "lanes_per_pass": job.lanes_per_pass, "pass_spp": job.pass_spp,
                "variant": variant}
    # the split `samples` makes is in the integrators' values only where n moved
    if job.samples is not None:
        settings["samples"] = job.samples
    if job.denoising.method != "off":  # frames in this process are denoised
        settings["denoise"] = job.denoising.method
    if job.data_passes:  # the frames' channels
        from styletrace.kernel.data_passes import parse_passes
        settings["passes"] = list(parse_passes(job.data_passes))
        if "mist" in settings["passes"] and job.mist is not None:  # the mist's own settings
            from styletrace.kernel.mist import parse_mist
            m = parse_mist(job.mist)
            settings["mist"] = [m.start, m.depth, m.falloff]
    return settings


__all__ = ["render_frames", "Manifest", "frame_settings"]
