"""Chunks of frames: the run of consecutive frames that one history of denoised estimates spans.

    scene = FrameScene.of(resolved, variant)                # what every frame of a scene shares
    frames = [Frame(scene, camera_rows, motion_rows), ...]   # a turntable's, or one per file
    for chunk in chunks_of(frames, size=8, reuse=True):
        for i, path in render_chunk(chunk, paths, skip): ...  # each frame written, in order

A chunk is the unit of work of command-line frames: in this process one after the other
(`animation.frames.render_frames`), on Ray one task each (`animation.ray_frames`), and both run
`render_chunk`, so a frame is the same bit for bit wherever its chunk ran. Every frame is a run of
the render pipeline (`pipeline.runner.Runner`, in this process, the finisher of its method:
`denoise.finishers.finisher_for`) with the scene's camera placed at the frame's.

With temporal reuse (`Chunk.reuse`) a frame that is denoised renders with its own seed
(`frame_seed`: independent estimates) and blends with a `denoise.temporal.History` of the chunk's
frames before it, as Blender's Render Animation does (docs/temporal.md): per frame its Depth,
Normal and Vector (`REUSE_PASSES`, with the cameras of the frames around; a list of files knows no
motion: its vector is 0, and the history's own depth, normal and brightness tests start again what
moved), `History.start` with the frame's settings but the seed (`history_key`), and the finisher
commits. The history starts afresh at each chunk's first frame, which therefore has none. Without
reuse, or where a frame is not denoised, every frame keeps the render's seed (the noise pattern
stays put) and blends with nothing.
"""
from __future__ import annotations

from dataclasses import dataclass, replace
from typing import Any, Iterator

import numpy as np

from styletrace.errors import StyletraceError
from styletrace.pipeline.job import Job
from styletrace.pipeline.ray_describe import SceneSpec

#: seeds are 32-bit (`scene.arguments.SEED_MAX`)
SEEDS = 1 << 32
#: the data passes each reused frame traces for its history: where its pixels' surfaces are
REUSE_PASSES = ("depth", "normal", "vector")
#: frames per chunk unless `--chunk` says otherwise
CHUNK = 8


def frame_seed(seed: int, frame: int) -> int:
    """The seed of frame `frame` (0-based) with temporal reuse: `seed + frame` modulo 2^32 (frame 0
    keeps `seed`), as Blender's `blender.animation.frame_seed`.

    Args:
        seed: the render's seed (>= 0). frame: the frame's index.

    Returns:
        The seed in [0, 2^32).
    """
    return (int(seed) + int(frame)) % SEEDS


class FrameStopped(StyletraceError):
    """A frame's run stopped or failed after some of its passes (what it finished is written to
    its path, not recorded): the sequence ends there.

    Args:
        frame: the frame's index. status: the run's exit status (`Runner.write`).
    """

    def __init__(self, frame: int, status: int):
        super().__init__(f"frame {frame} stopped before its last pass (exit status {status}): the "
                         f"frames before it are written; --resume continues")
        self.frame, self.status = frame, status

    def __reduce__(self):  # raised in a Ray worker, raised again in the driver as itself
        return (FrameStopped, (self.frame, self.status))


@dataclass(frozen=True)
class FrameScene:
    """What the frames of one scene share, in a form that pickles (a Ray task receives it).

    Args:
        spec: the scene, its size, defines and sampler (`ray_describe.SceneSpec`).
        values: the resolved integrator's property values (`auto` values pinned).
        job: the job's other settings (spp, seed, samples, pass split, denoising with its method
            pinned, data passes), its scene and integrator left out.
        variant: the Mitsuba variant.
    """
    spec: SceneSpec
    values: dict
    job: Job
    variant: str

    @classmethod
    def of(cls, resolved, variant: str) -> "FrameScene":
        """The frames' scene of a resolved job (its integrator's values, its method pinned).

        Args:
            resolved: the scene's `pipeline.resolve.Resolved` job. variant: Mitsuba's variant.

        Returns:
            The FrameScene.

        Raises:
            UsageError: an integrator without property values, or a scene that cannot travel.
        """
        from styletrace.pipeline.ray_run import job_for
        job = resolved.job
        load = {"defines": dict(job.defines)} if job.defines else {}
        if job.sampler is not None:
            load["sampler"] = job.sampler
        travel = job_for(job.scene, resolved.integrator, job.width, job.height, **load)
        denoising = replace(job.denoising, method=resolved.method, history=None)
        rest = job.with_(scene=None, given={}, integrator=None, motion=None, denoising=denoising)
        return cls(travel.spec, travel.values, rest, variant)

    def resolve(self):
        """This scene's job resolved here (`pipeline.resolve.resolve`, in this process): the same
        in the driver and in any Ray worker, with the driver's integrator values.

        Returns:
            The `Resolved` job.
        """
        from styletrace.kernel.integrator import StylizedIntegrator
        from styletrace.pipeline.ray_describe import _decode
        from styletrace.pipeline.resolve import resolve
        from styletrace.scene import plugins
        plugins.init(self.variant)
        s = self.spec
        scene = _decode(s.scene) if isinstance(s.scene, dict) else s.scene
        job = self.job.with_(scene=scene, width=s.width, height=s.height,
                             defines=dict(s.load_kwargs.get("defines") or {}),
                             sampler=s.load_kwargs.get("sampler"),
                             integrator=StylizedIntegrator.from_values(self.values))
        return resolve(job, local=True)


def rows(matrix: Any) -> tuple | None:
    """A 4x4 matrix as 4 rows of 4 floats (None stays None): a camera that pickles."""
    if matrix is None:
        return None
    return tuple(tuple(float(v) for v in row) for row in np.asarray(matrix, np.float64))


@dataclass(frozen=True)
class Frame:
    """One frame: its scene, its camera and the cameras of the frames around it.

    Args:
        scene: its `FrameScene` (a turntable's frames share one).
        camera: the sensor's to_world as 4 rows of 4 (`rows`), or None: the scene's own.
        motion: (the previous frame's camera, the next one's), each 4 rows of 4, or None: no
            motion known (a list of files; a still's vector is 0).
    """
    scene: FrameScene
    camera: tuple | None = None
    motion: tuple | None = None


@dataclass(frozen=True)
class Chunk:
    """Consecutive frames that one history spans.

    Args:
        first: the index of its first frame. frames: its frames, in order.
        reuse: temporal reuse asked for (it applies to the frames that are denoised).
    """
    first: int
    frames: tuple
    reuse: bool

    @property
    def indices(self) -> range:
        return range(self.first, self.first + len(self.frames))


def chunks_of(frames: list[Frame], size: int, reuse: bool) -> list[Chunk]:
    """The frames split into chunks of `size` consecutive frames (the last one may be shorter).

    Args:
        frames: every frame, in order. size: frames per chunk (>= 1). reuse: temporal reuse.

    Returns:
        The chunks, in order.
    """
    return [Chunk(k, tuple(frames[k:k + size]), reuse) for k in range(0, len(frames), size)]


def history_key(resolved) -> tuple:
    """What a frame's view is, for its history (`History.start`): every setting of the frame but
    the seed (the integrator's values, the camera samples and their split, the size, the
    denoising), compared by value. The scene is not in it: what moved between two frames or two
    files is the reprojection's and the history's tests' to find (docs/temporal.md).

    Args:
        resolved: the frame's `Resolved` job.

    Returns:
        A tuple of plain values.
    """
    job = resolved.job
    d = job.denoising
    return (repr(sorted(resolved.integrator.values.items())), resolved.spp, resolved.size,
            resolved.lanes, job.pass_spp, job.pass_growth, resolved.method, d.quality,
            d.coverage, d.uncertainty, d.footprint, tuple(job.data_passes))


def _motion(frame: Frame):
    from styletrace.kernel.data_passes import Motion
    if frame.motion is None:
        return None
    return Motion(np.asarray(frame.motion[0]), np.asarray(frame.motion[1]))


def render_chunk(chunk: Chunk, paths: dict, skip: set | frozenset = frozenset()
                 ) -> Iterator[tuple[int, str]]:
    """Render a chunk's frames in this process, in order, each into its path (module doc).

    A frame in `skip` is not written; with reuse it still renders (the history of the frames
    after it needs it) where a frame after it is to be written, and without reuse it does not
    render at all.

    Args:
        chunk: the chunk. paths: {frame index: the image's path} for the frames to write.
        skip: the indices not to write (written already).

    Returns:
        An iterator of (frame index, the path written: another one where the target could not be
        replaced), after each frame is written.

    Raises:
        FrameStopped: a frame's run stopped or failed after some passes (`Runner.write`'s status).
        UsageError: a refusal of a frame's run (one line).
    """
    from styletrace.denoise.finishers import finisher_for
    from styletrace.denoise.temporal import FrameView, History
    from styletrace.kernel.data_passes import placed, render_data_passes
    from styletrace.pipeline.execute import InProcess
    from styletrace.pipeline.runner import Runner, Voice
    todo = [i for i in chunk.indices if i not in skip]
    if not todo:
        return
    history = History() if chunk.reuse else None
    scene, resolved = None, None
    for i, frame in zip(chunk.indices, chunk.frames):
        if i > todo[-1]:  # what comes after the last frame to write serves nothing
            return
        if frame.scene is not scene and frame.scene != scene:  # a new scene: loaded once
            scene, resolved = frame.scene, frame.scene.resolve()
        reuse = history is not None and resolved.method != "off"
        if i in skip and not reuse:
            continue
        job = resolved.job.with_(motion=_motion(frame))
        if reuse:
            job = job.with_(seed=frame_seed(job.seed, i),
                            denoising=replace(job.denoising, history=history))
        frame_resolved = replace(resolved, job=job)
        sensor = resolved.scene.sensors()[0]
        # the scene's own camera placed at the frame's for the whole run: the passes, the data
        # passes and the denoiser's guides and points see the frame's
        with placed(sensor, None if frame.camera is None else np.asarray(frame.camera)):
            runner = Runner(frame_resolved, InProcess(), finisher_for(frame_resolved))
            if reuse:  # where this frame's surfaces were in the frames before (docs/temporal.md)
                seen = render_data_passes(resolved.scene, REUSE_PASSES, resolved.spp, job.seed,
                                          job.motion)
                history.start(history_key(frame_resolved),
                              FrameView.from_passes(seen["depth"], seen["normal"],
                                                    seen["vector"]))
            if i in skip:  # its history only: the frame itself is written already
                runner.result()
                continue
            status = runner.write(paths[i], Voice(quiet=True))
        if runner.written is None:  # stopped, or a pass failed: its finished passes are written
            raise FrameStopped(i, status)
        yield i, runner.written.path


__all__ = ["Frame", "FrameScene", "Chunk", "FrameStopped", "chunks_of", "render_chunk",
           "frame_seed", "history_key", "rows", "REUSE_PASSES", "SEEDS", "CHUNK"]
