"""The command line's hand-off: `styletrace render --ray [ADDRESS] [--resume]` and `--frames`.

    executor = executor_of(args)        # pipeline.execute.OnRay: a run.Render, with save()/finish()
    status = frames_command(args, parse_set, parse_defines, check_output, say)

`--ray` renders one image through the pipeline's runner (`pipeline.runner.Runner`) with this
executor: its loop, progress bar and signal handling, and `save()` before it abandons a render on a
second Ctrl-C, so the checkpoint holds every finished pass. Frames (`--frames`, several files) are
runs of the same runner in this process's pipeline, in chunks of `--chunk` with the temporal reuse
of `--temporal-reuse` (`animation.frame_chunks`): here one chunk after the other
(`animation.frames.render_frames`), with `--ray` each chunk one Ray task
(`animation.ray_frames.render_frames_on_ray`).
"""
from __future__ import annotations

import os
import re
import sys

from styletrace.errors import UsageError
from styletrace.pipeline.ray_cluster import LOCAL

_ADDRESS = re.compile(r"^(auto|ray://.+|[^\s:/]+:\d+)$")


def cluster_of(args) -> str:
    """The cluster of `--ray [ADDRESS]` (and of `--resume` alone: a local one).

    Args:
        args: the parsed arguments of `styletrace render`.

    Returns:
        "local" or the address.

    Raises:
        UsageError: an address that is not HOST:PORT, ray://HOST:PORT or auto.
    """
    address = args.ray if args.ray is not None else LOCAL
    if address != LOCAL and not _ADDRESS.match(address):
        raise UsageError(f"bad --ray address {address!r}: expected HOST:PORT, ray://HOST:PORT or "
                         f"auto (written after the scene, or as --ray=ADDRESS)")
    return address


def executor_of(args):
    """Where the command's passes run.

    Args:
        args: the parsed arguments (`ray`, `resume`, `output`, `checkpoint_every`).

    Returns:
        `pipeline.execute.InProcess`, or with `--ray [ADDRESS]` / `--resume` an `OnRay` on the
        cluster, checkpointed next to the output (every 10 s unless `--checkpoint-every`).

    Raises:
        UsageError: a negative `--checkpoint-every`, or a bad address.
    """
    from styletrace.pipeline.execute import InProcess, OnRay
    from styletrace.pipeline.ray_checkpoint import Checkpoints
    if args.ray is None and not args.resume:
        return InProcess()
    if args.checkpoint_every is not None and args.checkpoint_every < 0:
        raise UsageError(f"bad value {args.checkpoint_every} for --checkpoint-every: expected "
                         f"seconds >= 0")
    every = 10.0 if args.checkpoint_every is None else args.checkpoint_every
    return OnRay(cluster_of(args), checkpoints=Checkpoints(args.output, args.resume, every))


def frame_paths(output: str, count: int) -> list[str]:
    """The numbered images of a sequence: out.png -> out_0000.png, out_0001.png, ...

    Args:
        output: the sequence's output path. count: how many frames.

    Returns:
        The paths, in frame order.
    """
    stem, ext = os.path.splitext(output)
    return [f"{stem}_{i:04d}{ext}" for i in range(count)]


def turntable_frames(scene, loaded, count: int, degrees: float, motion: bool) -> list:
    """A turntable's frames: each on its camera; with `motion` (a Vector pass asked for, or
    temporal reuse) each also carries the cameras of the frames before and after it (the turn goes
    on past the first and the last frame).

    Args:
        scene: the frames' `animation.frame_chunks.FrameScene`. loaded: its loaded mi.Scene (the
            camera the turn starts from). count: how many frames. degrees: the whole turn.
        motion: give each frame the cameras around it.

    Returns:
        [`animation.frame_chunks.Frame`] in frame order.
    """
    from styletrace.animation.frame_chunks import Frame, rows
    from styletrace.pipeline.orbit import turntable
    if not motion:
        return [Frame(scene, rows(m)) for m in turntable(loaded, count, degrees)]
    cams = turntable(loaded, count, degrees, -1, count + 1)
    return [Frame(scene, rows(cams[k + 1]), (rows(cams[k]), rows(cams[k + 2])))
            for k in range(count)]


def check_chunk(chunk) -> int:
    """`--chunk N`: frames per chunk (`animation.frame_chunks.CHUNK` where not given).

    Args:
        chunk: the parsed value, or None.

    Returns:
        The frames per chunk.

    Raises:
        UsageError: a value below 1.
    """
    from styletrace.animation.frame_chunks import CHUNK
    if chunk is None:
        return CHUNK
    if chunk < 1:
        raise UsageError(f"bad value {chunk} for --chunk: expected a whole number of frames >= 1")
    return chunk


def frames_command(args, parse_set, parse_defines, check_output, say) -> int:
    """`styletrace render SCENE --frames N [--orbit DEGREES]`, or `render A.xml B.xml ...`: the
    frames in chunks of `--chunk` (`animation.frame_chunks`), each frame denoised as `--denoise`
    asks and, with `--temporal-reuse on` (the default), blended with its chunk's frames before
    it; in this process, or with `--ray` each chunk one Ray task running the same pipeline.

    Args:
        args: the parsed arguments. parse_set, parse_defines: the parsers of --set and -D.
        check_output: the check of an output path. say: the one-line messages.

    Returns:
        The exit status: 0, or that of the frame that stopped or failed (130: Ctrl-C between two,
        or on Ray).

    Raises:
        UsageError: bad flags or counts, a bad output or scene, or a refusal of the frames' runs,
            before any frame renders (each scene is resolved first, `pipeline.resolve`); a
            refusal in a frame's run (on Ray too) after the frames before it are written.
    """
    from styletrace.animation.frame_chunks import Frame, FrameScene, chunks_of
    from styletrace.animation.frames import Manifest, frame_settings, render_frames
    from styletrace.denoise.finishers import finisher_for
    from styletrace.frontends.command_job import job_of
    from styletrace.pipeline.execute import InProcess
    from styletrace.pipeline.job import check_counts
    from styletrace.pipeline.resolve import resolve
    from styletrace.pipeline.runner import Runner
    from styletrace.pipeline.signals import one_line
    from styletrace.pipeline.sizing import lanes_per_pass
    from styletrace.scene.plugins import init

    scenes = args.scene or ["cornell-box"]
    if len(scenes) > 1 and (args.frames is not None or args.orbit is not None):
        raise UsageError("--frames/--orbit turn one scene into a turntable; with several scene "
                         "files each file is one frame")
    check_counts(("--frames", args.frames))
    if args.orbit is not None and args.frames is None:
        raise UsageError("--orbit needs --frames N (how many frames the rotation is split into)")
    check_counts(("--width", args.width), ("--height", args.height), ("--spp", args.spp),
                 ("--samples", args.samples), ("--pass-spp", args.pass_spp))
    chunk = check_chunk(args.chunk)
    reuse = args.temporal_reuse == "on"
    for scene in scenes:
        check_output(args.output, scene)
    count = args.frames if len(scenes) == 1 else len(scenes)
    paths = frame_paths(args.output, count)
    from styletrace.images import check_target
    # every numbered image and the manifest, as the output
    for path in paths + [args.output + ".frames.json"]:
        check_target(path)
    params = parse_set(args.set)
    defines = parse_defines(args.define)
    cluster = cluster_of(args) if args.ray is not None else None  # None: in this process
    variant = init()
    lanes, note = lanes_per_pass(variant)
    if note and not args.quiet:
        say(f"styletrace: {note}")
    frames, values, specs, spps, methods = [], [], [], [], []
    for name in scenes:  # each file resolved here once: a broken one fails before any frame renders
        asked = job_of(args, params, defines, scene=name).with_(lanes_per_pass=lanes)
        # in this process or in a Ray worker alike, each frame is a run of this process's pipeline
        resolved = resolve(asked)
        spps.append(resolved.spp)
        methods.append(resolved.method)
        if resolved.auto and not args.quiet:  # as a single image's run says them, to pin them
            which = f"{one_line(name)}: " if len(scenes) > 1 else ""
            say(f"styletrace: auto values: {which}{resolved.auto}")
        # the refusals of its frames' runs (the output's too), before any renders
        Runner(resolved, InProcess(), finisher_for(resolved)).check_output(paths[0])
        scene = FrameScene.of(resolved, variant)
        if len(scenes) == 1:  # a turntable: every frame of this scene, each on its camera
            degrees = 360.0 if args.orbit is None else args.orbit
            moves = "vector" in resolved.job.data_passes or (reuse and resolved.method != "off")
            frames = turntable_frames(scene, resolved.scene, count, degrees, moves)
        else:  # a file's frame: no motion known (its vector 0), loaded again when it comes
            frames.append(Frame(scene))
        values.append(scene.values)
        specs.append(scene.spec.describe())
        del resolved
    # reuse changes only the frames that are denoised: the manifest says so only where it does
    reused = reuse and any(m != "off" for m in methods)
    settings = frame_settings("orbit" if len(scenes) == 1 else "files", specs, values, count,
                              args.orbit, asked, variant, chunk if reused else None)
    manifest = Manifest(args.output, settings)
    chunks = chunks_of(frames, chunk, reuse)
    bar = None
    if not args.quiet:
        from tqdm import tqdm
        bar = tqdm(total=count, unit="frame", desc="rendering", file=sys.stderr)

    def on_frame(i, out):
        if bar is not None:
            bar.update(1)

    try:
        if cluster is None:
            written, status = render_frames(chunks, paths, manifest, resume=args.resume,
                                            on_frame=on_frame)
        else:
            from styletrace.animation.ray_frames import render_frames_on_ray
            written, status, _ = render_frames_on_ray(chunks, paths, manifest, cluster,
                                                      resume=args.resume, on_frame=on_frame)
    except KeyboardInterrupt:  # between two frames' runs, or on Ray (a run here stops on its own)
        status = 130
    finally:
        if bar is not None:
            bar.close()
    if status:
        stopped = "interrupted; " if status >= 128 else ""
        say(f"styletrace: {stopped}{len(manifest.done)} of {count} frames written "
            f"(--resume continues)")
        return status
    if not args.quiet:
        # the resolved split's camera samples (--spp may be absent), one value per distinct count
        spp = ", ".join(str(n) for n in sorted(set(spps)))
        where = "" if cluster is None else ", on Ray"
        say(f"wrote {len(written)} frames {paths[0]} ... {paths[-1]} ({variant}, spp {spp}"
            f"{where})")
    return 0


__all__ = ["cluster_of", "executor_of", "frame_paths", "turntable_frames", "check_chunk",
           "frames_command"]
