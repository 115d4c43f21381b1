"""The denoisers as a run's finishers, and the run of a resolved job at every front end's default.

    runner, note = plan_finisher(resolve(job), method="auto", executor=InProcess(), buffer="b.npz")
    image = runner.result()                # or runner.write("out.exr", voice) on the command line

`Expectation` records the expectation buffer pass by pass and, after the last pass or a stop,
denoises it and applies g (`denoise.expectation.ExpectationJob`); `Image` denoises the average of
the finished passes (`denoise.image.finish_denoised_image`). `plan_finisher` picks the finisher of
a resolved job (`denoise.default.choose`: auto, expectation, image or off; off with `buffer`
records the buffer, `lookdev.record.Recorded`) and returns the one-line note where auto could not
denoise.
"""
from __future__ import annotations

from typing import Any, Callable

from styletrace.errors import UsageError
from styletrace.images import save_safely
from styletrace.pipeline.runner import Finisher, Plain, Runner, Written
from styletrace.scene.loading import film_format

#: why a denoiser needs the whole image in one process
LOCAL = ("--denoise renders locally: the denoiser needs the whole image in one process (no --ray, "
         "no cluster=)")
NOT_DENOISED = ", NOT denoised (the pass under way did not end)"


class Denoised(Finisher):
    """What both denoisers share: OIDN and an rgb film required, a pass on every pixel before a
    result.

    Args:
        quality: OIDN's "high", "balanced" or "fast".
        buffer: the file to keep the denoised expectation buffer in (or None; `Image` refuses one).
    """
    how = ", denoised,"
    local = LOCAL
    plain_note = NOT_DENOISED

    def __init__(self, quality: str = "high", buffer: str | None = None):
        self.quality, self.buffer = quality, buffer

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
        return save_safely(prog.image[..., :3], output, pixel_format, None, plain=True)


class Expectation(Denoised):
    """The per-pixel expectation denoised before g (`denoise.expectation`).

    Args:
        quality: OIDN's quality. buffer: the file to keep the denoised buffer in, or None.
        label: the buffer's scene label ('': from the scene). coverage: points per pixel where g
            meets D (`coverage.check_k`). uncertainty: `expectation.spread`'s (None: UNCERTAINTY).
        keep: called with the denoised buffer (Blender's Record buffer), or None.
        max_samples: the buffer's cap (None: MAX_SAMPLES).
        live: attach D after every pass to the buffer so far, at its camera samples
            (`expectation.attach`, k = 0), so that a restyle of it styles D (the preview's).
    """

    def __init__(self, quality: str = "high", buffer: str | None = None, label: str = "",
                 coverage: int | str = "auto", uncertainty: float | None = None,
                 keep: Callable[[Any], None] | None = None, max_samples: int | None = None,
                 live: bool = False):
        super().__init__(quality, buffer)
        from styletrace.denoise.expectation import UNCERTAINTY
        from styletrace.lookdev.buffer import MAX_SAMPLES
        self.label, self.coverage, self.keep, self.live = label, coverage, keep, live
        self.uncertainty = UNCERTAINTY if uncertainty is None else uncertainty
        self.max_samples = MAX_SAMPLES if max_samples is None else max_samples
        self.job = None

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
        expectation.check_expectation(resolved.integrator)
        check_film(resolved.scene)  # the buffer's conditions: an rgb film, a filter it can record
        if self.buffer is not None:
            from styletrace.lookdev.buffer import check_buffer_path
            check_buffer_path(self.buffer)
        job = resolved.job
        self.job = expectation.ExpectationJob(resolved.scene, resolved.integrator, resolved.spp,
                                              job.seed,
                                   self.quality, self.max_samples,
                                   label=self.label or scene_label(job.scene),
                                   coverage=self.coverage, uncertainty=self.uncertainty,
                                   lanes_per_pass=resolved.lanes, pass_spp=job.pass_spp,
                                   pilot=resolved.pilot)  # the resolve's: not traced again
        self.aovs = bool(resolved.integrator.settings.aovs)

    def source(self, resolved, executor, lock):
        from styletrace.denoise.expectation import attach
        for prog, buf in self.job.passes():
            if self.live:
                attach(buf, self.job.scene, buf.spp, self.job.seed, self.quality)
            yield prog

    def ready(self, prog) -> bool:
        return super().ready(prog) and self.job.buffer is not None and self.job.buffer.spp >= 1

    def _finish(self):
        image, buf = self.job.finish()
        if self.keep is not None:
            self.keep(buf)
        return image, buf

    def result(self, prog):
        from styletrace.denoise.expectation import aovs
        image, buf = self._finish()
        return (image, aovs(buf, image)) if self.aovs else image

    def write(self, prog, output: str, pixel_format: str) -> Written:
        from styletrace.denoise.expectation import aovs
        image, buf = self._finish()
        out = save_safely(image, output, pixel_format, aovs(buf, image) if self.aovs else None)
        if self.buffer is not None:
            buf.save(self.buffer)
        points = buf.header.get("denoise", {}).get("coverage")
        how = (f"expectation, the style at {points} points per pixel" if points else
               "expectation, the style at the camera samples")
        return Written(out, (self.buffer,) if self.buffer else (), image, f", denoised: {how}")


class Image(Denoised):
    """The average of the finished passes denoised (`denoise.image`), the baseline.

    Args:
        quality, buffer: as `Denoised`'s. footprint: "pixel" (each sample kept in its pixel where
            the film's filter is not a box: `denoise.image.in_pixels`) or "film" (the film's
            image as it is, the image denoiser before issue 37).
    """

    def __init__(self, quality: str = "high", buffer: str | None = None,
                 footprint: str = "pixel"):
        super().__init__(quality, buffer)
        from styletrace.denoise.image import check_footprint
        self.footprint = check_footprint(footprint)

    def check(self, resolved, executor) -> None:
        super().check(resolved, executor)
        if self.buffer is not None:
            raise UsageError("--buffer with --denoise image: the buffer keeps the expectation, "
                             "which image denoising leaves noisy; use --denoise expectation")
        self.scene, self.seed = resolved.scene, resolved.job.seed
        self.aovs = bool(resolved.integrator.aov_names())
        from styletrace.denoise.image import in_pixels
        self.in_pixels = (self.footprint == "pixel"
                          and in_pixels(resolved.scene, resolved.integrator))

    def source(self, resolved, executor, lock):
        """The executor's passes; on a film whose filter is not a box, each sample kept in its
        pixel (`denoise.image.in_pixels`; the finisher renders in this process only)."""
        if not self.in_pixels:
            return executor.source(resolved, lock)
        return executor.source(resolved, lock, in_pixels=True)

    def _finish(self, prog):
        from styletrace.denoise.image import finish_denoised_image
        return finish_denoised_image(self.scene, prog, self.seed, self.quality)

    def result(self, prog):
        out, _, errs = self._finish(prog)
        return (out, errs) if self.aovs else out

    def write(self, prog, output: str, pixel_format: str) -> Written:
        out, _, errs = self._finish(prog)
        return Written(save_safely(out, output, pixel_format, errs), (), out, ", denoised: image")


def plan_finisher(resolved, method: str | None = None, executor: Any = None,
                  buffer: str | None = None,
         quality: str = "high", coverage: int | str = "auto", uncertainty: float | None = None,
         label: str = "", keep: Callable[[Any], None] | None = None,
         footprint: str = "pixel") -> tuple[Runner, str]:
    """The run of a resolved job with the finisher of its denoising method.

    Args:
        resolved: the resolved job. method: auto, expectation, image, off (None: the default).
        executor: the pipeline's (None: in process). buffer: a file for the buffer, or None.
        keep: called with the buffer kept. quality, coverage, uncertainty, label: `Expectation`'s.
        footprint: `Image`'s.

    Returns:
        (the `pipeline.runner.Runner`, the one-line note where auto could not denoise, else '').

    Raises:
        UsageError: a refusal of the run (one line), before anything renders.
    """
    from styletrace.denoise.default import choose
    from styletrace.pipeline.execute import InProcess
    executor = executor if executor is not None else InProcess()
    chosen = choose(resolved, method, local=executor.local)
    if chosen.method == "expectation":
        finisher = Expectation(quality, buffer, label, coverage, uncertainty, keep)
    elif chosen.method == "image":
        finisher = Image(quality, buffer, footprint)
    elif buffer is not None or keep is not None:
        from styletrace.lookdev.record import Recorded
        finisher = Recorded(buffer, label, keep)
    else:
        finisher = Plain()
    return Runner(chosen.resolved, executor, finisher), chosen.note


__all__ = ["Expectation", "Image", "plan_finisher", "LOCAL"]
