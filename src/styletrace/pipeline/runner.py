"""One way to run a job, for every front end: the passes, the checks, stops, the passes written.

    runner = Runner(resolve(job), InProcess(), Plain())
    image = runner.result(callback)                 # the Python API: image, or (image, aovs)
    status = runner.write("out.exr", Voice())        # the command line: an exit status
    for prog in runner.passes(): ...                # Blender, the preview: own loop, then finish()

A run is a resolved job (`resolve.resolve`), an executor yielding a `passes.Progress` after each
pass (`execute.InProcess`, `execute.OnRay`) and a finisher making the result (`Plain` here, the
denoisers' of `denoise.finishers`, `lookdev.record.Recorded`). `Runner.check` holds the refusals
that depend on the three. Design: docs/design/render_pipeline.md.
"""
from __future__ import annotations

import contextlib
import os
import sys
from dataclasses import dataclass
from typing import Any, Callable, Iterator

import numpy as np

from styletrace.errors import UsageError
from styletrace.gate import mi
from styletrace.images import check_format, nonfinite_pixels, save_safely
from styletrace.kernel.error_aovs import has_error_aovs
from styletrace.pipeline.passes import Progress, check_memory, pass_count
from styletrace.pipeline.resolve import Resolved
from styletrace.pipeline.signals import Passes, StopSignals, say
from styletrace.scene.loading import film_format, first_line


@dataclass
class Written:
    """What a finisher wrote: the image's path (another one where the target could not be replaced),
    the other files, the image itself (for the warnings) and a note for the summary line ('' for
    none)."""
    path: str
    extra: tuple[str, ...] = ()
    image: np.ndarray | None = None
    note: str = ""


class Finisher:
    """What a run makes of its finished passes (the base: the passes as they are, `Plain`).

    `how`: words for a stopped run's line (", denoised,"); `local`: why it needs the passes in this
    process ('' where it does not); `plain_note`: what a write that cannot wait for the pass under
    way leaves out; `data`: the run's data passes by key (`kernel.data_passes`), which the runner
    sets before the passes and every result and file carries beside the error AOVs (`channels`)."""
    how = ""
    local = ""
    plain_note = ""
    data: dict | None = None

    def channels(self, aovs: dict | None) -> dict | None:
        """The extra channels of a result or a file: the error AOVs, then the run's data passes.

        Args:
            aovs: the error AOVs by key (None: none).

        Returns:
            The AOVs with the data passes added; None where there are neither.
        """
        if not self.data:
            return aovs
        return {**(aovs or {}), **self.data}

    def check(self, resolved: Resolved, executor: Any) -> None:
        """Refusals of this finisher (one line each), before anything renders.

        Args:
            resolved: the resolved job. executor: the run's executor (`local`: whether in process).

        Raises:
            UsageError: what this finisher cannot finish (the base refuses nothing).
        """

    def source(self, resolved: Resolved, executor: Any, lock: Any) -> Iterator[Progress]:
        """The run's passes (the base: the executor's, as they are).

        Args:
            resolved: the resolved job. executor: the run's executor.
            lock: held while the running sum changes.

        Returns:
            An iterator of `Progress`.
        """
        return executor.source(resolved, lock)

    def ready(self, prog: Progress | None) -> bool:
        """Whether the finished passes make a result (some finishers need a pass on every pixel).

        Args:
            prog: the last finished pass's `Progress`, or None before the first.

        Returns:
            True where a result can be made (the base: after any pass).
        """
        return prog is not None

    def result(self, prog: Progress) -> Any:
        """The Python API's result of the finished passes.

        Args:
            prog: the last finished pass's `Progress`.

        Returns:
            The image, or (image, aovs) where the integrator has error AOVs or the run has data
            passes (`channels`).
        """
        aovs = self.channels(prog.aovs)
        return (prog.image, aovs) if aovs is not None else prog.image

    def write(self, prog: Progress, output: str, pixel_format: str) -> Written:
        """Write the result of the finished passes (the base: the image, with its error AOVs and
        data passes).

        Args:
            prog: the last finished pass's `Progress`. output: the image's path.
            pixel_format: the film's pixel format (`scene.loading.film_format`).

        Returns:
            What was written (`Written`: another path where the target could not be replaced).
        """
        return Written(save_safely(prog.image, output, pixel_format, self.channels(prog.aovs)),
                       image=prog.image)

    def write_plain(self, prog: Progress, output: str, pixel_format: str) -> str:
        """The finished passes as they are, written without Mitsuba (its writer waits for a running
        kernel).

        Args:
            prog: the last finished pass's `Progress`. output: the image's path.
            pixel_format: the film's pixel format.

        Returns:
            The path written.
        """
        return save_safely(prog.image, output, pixel_format, self.channels(prog.aovs), plain=True)


class Plain(Finisher):
    """The average of the finished passes, with its error AOVs where the integrator has them (and
    the run's data passes)."""


@dataclass
class Voice:
    """How a run that writes files speaks: `quiet` (no bar, notes or summary), the stderr status
    line of long waits (`frontends.status.Status`, or None)."""
    quiet: bool = False
    status: Any = None


class Runner:
    """A resolved job run by an executor and finished by a finisher (see the module doc).

    Args:
        resolved: the resolved job (`resolve.resolve`).
        executor: `execute.InProcess` or `execute.OnRay`.
        finisher: what makes the result (None: `Plain`).

    Raises:
        UsageError: a refusal of `check` (one line), made here.
    """

    def __init__(self, resolved: Resolved, executor: Any, finisher: Finisher | None = None):
        self.resolved, self.executor = resolved, executor
        self.finisher = finisher if finisher is not None else Plain()
        #: what the last `write` wrote of a run that finished every pass (None: stopped or failed)
        self.written: Written | None = None
        self._data: dict | None = None
        self.check()

    @property
    def aovs(self) -> bool:
        return has_error_aovs(self.resolved.integrator)

    def check(self) -> None:
        """The refusals that depend on the job, the executor and the finisher, one copy each."""
        # the finisher's refusal is the specific one
        self.finisher.check(self.resolved, self.executor)
        spp = self.resolved.spp
        if self.aovs and spp < 2:
            name = self.resolved.job.terms.name("spp")
            raise UsageError(f"bad value {spp} for {name} with aovs=True: the variance needs at "
                             f"least 2 camera samples per pixel")
        if self.finisher.local and not self.executor.local:
            raise UsageError(self.finisher.local)
        if self.resolved.integrator.aov_names() and not self.executor.local:
            raise UsageError("aovs=True and light_groups render without cluster=/--ray: the Ray "
                             "passes keep the image only")
        if "vector" in self.resolved.job.data_passes:  # a camera no pixel map projects
            from styletrace.kernel.data_passes import View
            View.of(self.resolved.scene.sensors()[0])

    def data_passes(self) -> dict:
        """The job's data passes (Depth, Normal, Vector, ...: `kernel.data_passes`), traced once, in
        this process, with the render's camera samples per pixel and seed; on the frame's camera
        where the executor renders one (a turntable's, `execute.OnRay.camera`).

        Returns:
            {key: float32 array}; empty where none were asked for.
        """
        if self._data is None:
            from styletrace.kernel.data_passes import render_data_passes
            r = self.resolved
            self._data = render_data_passes(r.scene, r.job.data_passes, r.spp, r.job.seed,
                                            r.job.motion,
                                            camera=getattr(self.executor, "camera", None),
                                            mist=r.job.mist)
        return self._data

    def check_output(self, output: str) -> str:
        """Refusals of the output file (its format, the memory of its write).

        Args:
            output: the image's path; its extension decides the format.

        Returns:
            The film's pixel format.

        Raises:
            UsageError: a format the film cannot be written in, too little memory, aovs or data
                passes but no .exr.
        """
        fmt = film_format(self.resolved.scene)
        ext = os.path.splitext(output)[1].lower()
        try:
            check_format(fmt, ext)
        except ValueError as exc:
            raise UsageError(f"bad output {output!r}: {exc}") from None
        check_memory(*self.resolved.size, ext)
        if self.aovs and ext != ".exr":
            raise UsageError(f"bad output {output!r}: --aovs writes its channels into an .exr; a "
                             f"{ext} image has no room for them")
        if self.resolved.job.data_passes and ext != ".exr":
            passes = self.resolved.job.terms.name("passes")
            raise UsageError(f"bad output {output!r}: {passes} writes its channels into an .exr; "
                             f"a {ext} image has no room for them")
        return fmt

    def passes(self, lock: Any = contextlib.nullcontext()) -> Iterator[Progress]:
        """The passes, the running state after each (a caller may stop taking them at any time).

        Args:
            lock: held while the running sum changes (default: no lock).

        Returns:
            An iterator of `Progress`.
        """
        return self.finisher.source(self.resolved, self.executor, lock)

    def finish(self, prog: Progress) -> Any:
        """The result of the finished passes up to `prog` (the finisher's).

        Args:
            prog: the last finished pass's `Progress`.

        Returns:
            The finisher's result: the image, or (image, aovs); the data passes are in it only
            after `result` or `write` (a caller with its own loop takes them from `data_passes`).
        """
        return self.finisher.result(prog)

    def result(self, callback: Callable[[Progress], None] | None = None) -> Any:
        """Every pass, then the result.

        Args:
            callback: called with the `Progress` after each pass, or None.

        Returns:
            The finisher's result (`finish`), with the data passes asked for.
        """
        self.finisher.data = self.data_passes()
        prog = None
        for prog in self.passes():
            if callback is not None:
                callback(prog)
        return self.finish(prog)

    def write(self, output: str, voice: Voice | None = None) -> int:
        """Run to files, as the command line does; Ctrl-C or SIGTERM stop after the pass under way.

        Args:
            output: the image's path. voice: how the run speaks (None: `Voice()`).

        Returns:
            The exit status: 0; 1 where a later pass failed or the image went to another path;
            128 + the signal's number after Ctrl-C or SIGTERM. The finished passes are written.

        Raises:
            UsageError: a refusal of the output (`check_output`). A pass's own error is raised
                where no pass that makes a result finished before it.
        """
        self.written = None
        voice = voice or Voice()
        status = voice.status if voice.status is not None else _Silent()
        r, finisher = self.resolved, self.finisher
        fmt = self.check_output(output)
        # before the passes: a stopped run writes them too, with no kernel to wait for
        finisher.data = self.data_passes()
        if r.auto and not voice.quiet:  # scene-relative defaults, printed to pin them
            say(f"styletrace: auto values: {r.auto}")
        if r.lanes_note and not voice.quiet:
            say(f"styletrace: {r.lanes_note}")
        spp = r.spp
        run = Passes(spp, pass_count(r.scene, spp, r.lanes, pass_spp=r.job.pass_spp), voice.quiet)
        source = None

        # from the watcher thread: the pass under way is lost, the finished ones are not
        def abandon(signum):
            status.stop()
            if hasattr(source, "save"):  # a render on Ray: its checkpoint gets every finished pass
                source.save()
            latest = run.latest
            if latest is None or not finisher.ready(latest):
                say("styletrace: interrupted before the first pass finished; nothing written")
            else:
                out = finisher.write_plain(latest, output, fmt)
                say(f"styletrace: interrupted; wrote {out} from {latest.spp_done} of {spp} spp"
                    f"{finisher.plain_note}")
            sys.stderr.flush()
            os._exit(128 + signum)  # the kernel under way cannot be stopped, nor waited for

        with StopSignals(abandon) as stop:
            try:
                source = self.passes(stop.lock)
                if run.bar is not None:
                    status.follow(run.bar)
                else:
                    status.start("compiling and rendering")
                run.follow(source, stop)
            finally:
                status.stop()
                run.close()
            with stop.lock:
                stop.settled = True
            # the final write happens under the watcher too: a signal now does not cut it
            latest, failure = run.latest, run.failure
            # a render on Ray: its checkpoint gets every finished pass now (not whenever its
            # iterator is collected)
            if stop.count and hasattr(source, "save"):
                source.save()
            if not finisher.ready(latest):
                if failure is not None:
                    raise failure
                say("styletrace: interrupted before every pixel had a pass; nothing written"
                    if latest is not None
                    else "styletrace: interrupted before the first pass finished; nothing written")
                return stop.exit_status
            done = finisher.write(latest, output, fmt)
        self._warn(done)
        outs = " and ".join((done.path, *done.extra))
        if failure is not None:
            say(f"styletrace: error after {latest.spp_done} of {spp} spp ({first_line(failure)}); "
                f"wrote the finished passes{finisher.how} to {outs}")
            return 1
        if stop.count:
            say(f"styletrace: interrupted; wrote the finished passes{finisher.how} to {outs} after "
                f"{latest.spp_done} of {spp} spp")
            return stop.exit_status
        self.written = done
        if done.path == output and hasattr(source, "finish"):
            source.finish()  # a render on Ray: the checkpoint has served
        if not voice.quiet:
            style = r.integrator.settings.style.describe()
            say(f"wrote {outs} ({mi.variant()}, {style}, spp {spp}{done.note})")
        return 0 if done.path == output else 1

    def _warn(self, done: Written) -> None:
        """Non-finite pixels, and values that look wild (a diverging estimator); after the write:
        the image is kept either way."""
        if done.image is None:
            return
        bad = nonfinite_pixels(done.image)
        if bad:
            png = done.path.lower().endswith(".png")
            fix = "NaN as 0 and +inf as 1 in the PNG" if png else "kept as they are"
            say(f"styletrace: warning: {bad} pixel(s) are not finite (NaN or inf): {fix}")
        from styletrace.wild import warning
        wild = warning(done.image, self.resolved.integrator.settings)
        if wild:
            say(f"styletrace: warning: {wild}")


class _Silent:
    """A status line that shows nothing (a run without one)."""

    def start(self, *_):
        pass

    def follow(self, *_):
        pass

    def stop(self):
        pass


__all__ = ["Runner", "Finisher", "Plain", "Written", "Voice"]
