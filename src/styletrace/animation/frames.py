"""Frames: a turntable of one scene (`--frames N --orbit DEGREES`) or a list of XML files.

    written, status = render_frames(chunks_of(frames, 8, reuse=True), paths, manifest)
    # out_0000.png, out_0001.png, ...; on Ray: animation.ray_frames.render_frames_on_ray

Frames render in chunks of consecutive frames (`animation.frame_chunks`): each frame a run of the
render pipeline (`pipeline.runner.Runner`, in this process) with the scene's camera placed at the
frame's, denoised as the job asks and, with temporal reuse, blended with the history of its chunk's
frames before it. Here the chunks render one after the other; on Ray each is one task
(`animation.ray_frames`), the same frames bit for bit. A frame written to its own path is recorded
in a manifest (`OUT.frames.json`, with the settings a resume must match: `frame_settings`), so
`--resume` renders only the chunks not yet written whole (a chunk partly written renders from its
first frame where its history needs the frames before, and writes only the missing ones). A stop
ends the sequence after the frame under way (its finished passes written, as the runner writes
them); the frames recorded stay.
"""
from __future__ import annotations

import json
from typing import Callable

from styletrace.animation.frame_chunks import FrameStopped, render_chunk
from styletrace.errors import UsageError
from styletrace.images import write_bytes_atomically


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


def render_frames(chunks: list, paths: list[str], manifest: Manifest, resume: bool = False,
                  on_frame: Callable[[int, str], None] | None = None) -> tuple[list[int], int]:
    """Render the chunks' frames in this process, chunk after chunk (`frame_chunks.render_chunk`),
    each frame into its path and recorded in the manifest as it is written.

    Args:
        chunks: the `frame_chunks.Chunk`s, in order. paths: every frame's image.
        manifest: the written frames' manifest.
        resume: skip the frames the manifest names (a chunk they all fill is skipped whole).
        on_frame: called with (frame, path written) after each frame.

    Returns:
        (the frames written by this call, 0 or the exit status of the frame that stopped).

    Raises:
        UsageError: a refusal of a frame's run (one line); the frames written before stay.
    """
    skip = manifest.load() if resume else set()
    written: list[int] = []
    for chunk in chunks:
        try:
            for i, path in render_chunk(chunk, {i: paths[i] for i in chunk.indices}, skip):
                if path == paths[i]:
                    manifest.add(i)
                written.append(i)
                if on_frame is not None:
                    on_frame(i, path)
        except FrameStopped as stop:
            return written, stop.status
    return written, 0


def frame_settings(kind: str, scenes: list, values: list, count: int, orbit: float | None,
                   job, variant: str, chunk: int | None = None) -> dict:
    """The settings a frames manifest records: what a `--resume` must match.
    Takes more than 7 parameters: each is one of the recorded settings, from a different source
    (the scenes, the job, the backend, the command's flags).

    Args:
        kind: "orbit" or "files". scenes: the scenes' descriptions. values: their integrator values.
        count, orbit: frames, turn (degrees; None for files).
        job: the frames' `pipeline.job.Job` (any frame's: they share its spp, seed, `samples`
            (the paths per pixel given, or None) and pass split, `lanes_per_pass` set).
        variant: the Mitsuba variant.
        chunk: frames per chunk where temporal reuse applies to the frames (their seeds and
            history depend on it), else None.

    Returns:
        The settings, a dict (`samples`, `passes`, `temporal_reuse` and `chunk` only where given:
        manifests written before them resume).
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
    if chunk is not None:  # each frame its own seed, and a history within its chunk
        settings["temporal_reuse"] = "on"
        settings["chunk"] = chunk
    return settings


__all__ = ["render_frames", "Manifest", "frame_settings"]
