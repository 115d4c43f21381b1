"""The denoisers as a run's finishers, and the run of a job at every front end's default.

    runner = plan(job, executor=InProcess(), recording=Recording(path="b.npz"))
    runner.resolved.method, runner.resolved.note   # expectation | image | off, why auto did not
    image = runner.result()                        # or runner.write("out.exr", voice)

`plan` is what every front end calls (the command line, Python, F12, the viewport, the preview,
their drafts): the job resolved once (`pipeline.resolve.resolve`: the denoising method chosen, then
the samples split for it), and the finisher of that method (`finisher_for`). `Expectation` records
the expectation buffer pass by pass and, after the last pass or a stop, denoises it and applies g
(`denoise.expectation.ExpectationJob`); `Image` denoises the average of the finished passes
(`denoise.image.finish_denoised_image`); undenoised, a buffer asked for is recorded
(`lookdev.record.Recorded`), else the passes are the result (`Plain`). The denoising options travel
in the job (`Job.denoising`).
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Callable

from styletrace.errors import UsageError
from styletrace.images import save_safely
from styletrace.pipeline.denoising import Denoising, check_expectation
from styletrace.pipeline.resolve import Resolved, resolve
from styletrace.pipeline.runner import Finisher, Plain, Runner, Written
from styletrace.scene.loading import film_format


@dataclass(frozen=True)
class Recording:
    """What a run keeps of its expectation buffer.

    Args:
        path: the .npz file the buffer is written to (`--buffer`), or None.
        label: how the buffer names its scene ('': from the job's scene).
        keep: called with the buffer after the passes (Blender's Record buffer, the viewport), or
            None.
        restyled: the run's frames are restyled whatever its method (the preview's): the buffer
            is recorded without a path or `keep` too, and also where the image denoiser finishes
            the run (the raw buffer, each restyle of it denoised again: `Image.denoiser`); without
            it such a run keeps none (a restyle of the noisy buffer is not its image).
    """
    path: str | None = None
    label: str = ""
    keep: Callable[[Any], None] | None = None
    restyled: bool = False

    @property
    def wanted(self) -> bool:
        """Whether a buffer is asked for at all."""
        return self.path is not None or self.keep is not None or self.restyled


#: nothing kept
NOTHING = Recording()

#: why a denoiser needs its passes in this process
LOCAL = ("--denoise renders in this process: the denoiser needs every camera sample here (no "
         "--ray, no cluster=)")
NOT_DENOISED = ", NOT denoised (the pass under way did not end)"


class Denoised(Finisher):
    """What both denoisers share: OIDN and an rgb film required, a pass on every pixel before a
    result.

    Args:
        denoising: the options (`pipeline.denoising.Denoising`: quality, coverage, uncertainty,
            footprint).
        buffer: the file to keep the denoised expectation buffer in (or None; `Image` refuses one).
    """
    how = ", denoised,"
    local = LOCAL
    plain_note = NOT_DENOISED

    def __init__(self, denoising: Denoising, buffer: str | None = None):
        self.denoising, self.buffer = denoising, buffer
        self.quality = denoising.quality

    def check(self, resolved, executor) -> None:
        from styletrace.denoise import oidn
        oidn.require()
        oidn.check_quality(self.quality)
        fmt = film_format(resolved.scene)
        if fmt != "rgb":
            raise UsageError(f"--denoise needs an rgb film, not '{fmt}'")

    def ready(self, prog) -> bool:
        return prog is not None and prog.spp_done >= 1

    def write_plain(self, prog, output: str, pixel_format: str) -> str:
        return save_safely(prog.image[..., :3], output, pixel_format, self.channels(None),
                           plain=True)


class Expectation(Denoised):
    """The per-pixel expectation denoised before g (`denoise.expectation`).

    Args:
        denoising: the options (its quality, coverage and uncertainty). buffer: the file to keep
            the denoised buffer in, or None.
        label: the buffer's scene label ('': from the scene).
        keep: called with the denoised buffer (Blender's Record buffer, the viewport), or None.
    The buffer's cap is the job's (`Job.cap`), the one its split was made within.
    """

    def __init__(self, denoising: Denoising, buffer: str | None = None, label: str = "",
                 keep: Callable[[Any], None] | None = None):
        super().__init__(denoising, buffer)
        from styletrace.denoise.expectation import UNCERTAINTY
        self.label, self.keep = label, keep
        self.coverage = denoising.coverage
        self.uncertainty = UNCERTAINTY if denoising.uncertainty is None else denoising.uncertainty
        self.job = None
        #: the denoised buffer of the last `result` or `write` (None before)
        self.kept = None

    @property
    def recorded(self):
        """The noisy buffer of the passes so far (None before the first)."""
        return self.job.buffer if self.job is not None else None

    def check(self, resolved, executor) -> None:
        super().check(resolved, executor)
        from styletrace.denoise import expectation
        from styletrace.denoise.coverage import check_k
        from styletrace.lookdev.record import check_film, scene_label
        check_k(self.coverage)
        expectation.check_uncertainty(self.uncertainty)
        check_expectation(resolved.integrator)
        check_film(resolved.scene)  # the buffer's conditions: an rgb film, a filter it can record
        if self.buffer is not None:
            from styletrace.lookdev.buffer import check_buffer_path
            check_buffer_path(self.buffer)
        job = resolved.job
        from styletrace.pipeline.execute import shot_of, split_of
        self.job = expectation.ExpectationJob(shot_of(resolved), self.denoising, job.cap,
                                              self.label or scene_label(job.scene),
                                              split_of(resolved),
                                              resolved.pilot)  # the resolve's: not traced again
        self.aovs = bool(resolved.integrator.settings.aovs)

    def source(self, resolved, executor, lock):
        for prog, _ in self.job.passes():
            yield prog

    def ready(self, prog) -> bool:
        return super().ready(prog) and self.job.buffer is not None and self.job.buffer.spp >= 1

    def _finish(self):
        image, buf = self.job.finish()
        self.kept = buf
        if self.keep is not None:
            self.keep(buf)
        return image, buf

    def result(self, prog):
        from styletrace.denoise.expectation import aovs
        image, buf = self._finish()
        extra = self.channels(aovs(buf, image) if self.aovs else None)
        return (image, extra) if extra is not None else image

    def write(self, prog, output: str, pixel_format: str) -> Written:
        from styletrace.denoise.expectation import aovs
        image, buf = self._finish()
        out = save_safely(image, output, pixel_format,
                          self.channels(aovs(buf, image) if self.aovs else None))
        if self.buffer is not None:
            buf.save(self.buffer)
        points = buf.header.get("denoise", {}).get("coverage")
        how = (f"expectation, the style at {points} points per pixel" if points else
               "expectation, the style at the camera samples")
        return Written(out, (self.buffer,) if self.buffer else (), image, f", denoised: {how}")


class Image(Denoised):
    """The average of the finished passes denoised (`denoise.image`), the baseline; on Ray too,
    the driver denoising the merged image (not with each sample kept in its pixel, nor a recorded
    buffer: `local`).

    Args:
        denoising, buffer: as `Denoised`'s; the denoising's footprint: "pixel" (each sample kept in
            its pixel where the film's filter is not a box: `denoise.image.in_pixels`) or "film"
            (the film's image as it is, the image denoiser before issue 37).
        record: the passes record the raw expectation buffer (`recorded`), which `denoiser`
            denoises restyles of (the preview's). label: its scene label. keep: called with it
            after the passes, or None.
    """

    def __init__(self, denoising: Denoising, buffer: str | None = None, record: bool = False,
                 label: str = "", keep: Callable[[Any], None] | None = None):
        super().__init__(denoising, buffer)
        from styletrace.denoise.image import check_footprint
        self.footprint = check_footprint(denoising.footprint)
        self.record, self.label, self.keep = record, label, keep
        #: the raw buffer of the passes so far, where they record one (None before the first)
        self.recorded = None
        self._guides: dict = {}

    def check(self, resolved, executor) -> None:
        super().check(resolved, executor)
        if self.buffer is not None:
            raise UsageError("--buffer with --denoise image: the buffer keeps the expectation, "
                             "which image denoising leaves noisy; use --denoise expectation")
        self.scene, self.seed = resolved.scene, resolved.job.seed
        # the error AOVs only (a stylized integrator's; light groups' AOVs are no error AOVs)
        settings = getattr(resolved.integrator, "settings", None)
        self.aovs = bool(settings is not None and settings.aovs)
        from styletrace.denoise.image import in_pixels
        self.in_pixels = (self.footprint == "pixel"
                          and in_pixels(resolved.scene, resolved.integrator))
        if self.record:
            from styletrace.lookdev.record import check_recordable, scene_label
            if self.in_pixels:  # a restyle develops the film's image: its footprint is the film's
                raise UsageError("a recorded buffer denoised as an image needs denoise footprint "
                                 "'film' on a film whose filter is not a box")
            check_recordable(resolved.integrator.settings, [])
            self.label = self.label or scene_label(resolved.job.scene)
        # the merged image of the passes, wherever they ran, is all this denoiser needs (on Ray
        # the driver denoises it); each pixel's own samples, or a recorded buffer, are this
        # process's only
        self.local = LOCAL if (self.record or self.in_pixels) else ""

    def source(self, resolved, executor, lock):
        """The executor's passes; on a film whose filter is not a box, each sample kept in its
        pixel (`denoise.image.in_pixels`; the finisher renders in this process only); recording
        the raw buffer where asked (`record`)."""
        if self.record:
            return self._recorded(resolved)
        if not self.in_pixels:
            return executor.source(resolved, lock)
        return executor.source(resolved, lock, in_pixels=True)

    def _recorded(self, resolved):
        from styletrace.lookdev.record import record
        from styletrace.pipeline.execute import shot_of, split_of
        for prog, buf in record(shot_of(resolved), split_of(resolved), self.label,
                                resolved.job.cap, resolved.pilot):
            buf.image = prog.image
            self.recorded = buf
            yield prog
        if self.keep is not None:
            self.keep(self.recorded)

    def _finish(self, prog):
        from styletrace.denoise.image import finish_denoised_image
        history = self.denoising.history
        out = finish_denoised_image(self.scene, prog, self.seed, self.quality, history)
        if history is not None:  # a run finishes once (`Runner`), as ExpectationJob.finish
            history.commit()
        return out

    def denoiser(self, prog) -> Callable:
        """What denoises an image of the passes up to `prog` as `result` does: OIDN with the
        guides of as many camera samples (`denoise.image.denoise_like`), for restyles of the
        recorded buffer.

        Args:
            prog: the last finished pass's `Progress`.

        Returns:
            A function of an H x W x 3 image (a restyle of `recorded`) to its denoised image.
        """
        from styletrace.denoise.image import denoise_like
        return lambda image: denoise_like(self.scene, image, prog.spp_done, self.seed,
                                          self.quality, self._guides)

    def result(self, prog):
        out, _, errs = self._finish(prog)
        extra = self.channels(errs if self.aovs else None)
        return (out, extra) if extra is not None else out

    def write(self, prog, output: str, pixel_format: str) -> Written:
        out, _, errs = self._finish(prog)
        return Written(save_safely(out, output, pixel_format, self.channels(errs)), (), out,
                       ", denoised: image")


def finisher_for(resolved: Resolved, recording: Recording = NOTHING) -> Finisher:
    """The finisher of a resolved job's denoising method (`Resolved.method`).

    Args:
        resolved: the resolved job (its method and its job's denoising options).
        recording: what the run keeps of its buffer (`Recording`).

    Returns:
        `Expectation`, `Image`, `lookdev.record.Recorded` (off, with a buffer asked for), or
        `Plain`.
    """
    denoising = resolved.job.denoising
    r = recording
    if resolved.method == "expectation":
        return Expectation(denoising, r.path, r.label, r.keep)
    if resolved.method == "image":
        return Image(denoising, r.path, r.restyled, r.label, r.keep)
    if r.wanted:
        from styletrace.lookdev.record import Recorded
        return Recorded(r.path, r.label, r.keep, resolved.job.cap)
    return Plain()


def plan(job, executor: Any = None, scene: Any = None, recording: Recording = NOTHING) -> Runner:
    """The run of a job at its denoising: what every front end calls.

    Args:
        job: the `pipeline.job.Job` (its `denoising` says what was asked).
        executor: the pipeline's (None: in process); on Ray auto does not denoise.
        scene: the scene already loaded from `job.scene`, or None.
        recording: what the run keeps of its buffer (`Recording`).

    Returns:
        The `pipeline.runner.Runner`; its `resolved.method` and `resolved.note` say what it
        denoises and why auto did not.

    Raises:
        UsageError: a refusal of the job or of the run (one line), before anything renders.
    """
    from styletrace.pipeline.execute import InProcess
    executor = executor if executor is not None else InProcess()
    resolved = resolve(job, scene, local=executor.local)
    return Runner(resolved, executor, finisher_for(resolved, recording))


__all__ = ["Expectation", "Image", "Denoised", "Recording", "NOTHING", "plan", "finisher_for",
           "LOCAL"]
