"""`styletrace render --denoise expectation|image [--denoise-quality high] [--coverage K] [--buffer FILE]`.

`cli.cmd_render` hands over here after it has loaded the scene, built the integrator and pinned its `auto`
values (so `--denoise` refuses, in one line and with exit status 2, before anything renders). The output is
written atomically (`images.save_safely`); with `--aovs` the EXR gets the honest channels of
`denoise.expectation.aovs` / `denoise.image.render`; with `--buffer` (expectation only) the buffer keeps the
denoised expectation, so `styletrace restyle` styles it.
"""
from __future__ import annotations

import os
import sys

from ..errors import UsageError
from ..pipeline.scene import first_line
from . import check_method


def precheck(args, scene, integrator, pixel_format: str) -> None:
    """Every refusal of `--denoise`, before the scene's defaults are resolved and anything renders."""
    method = check_method(args.denoise)
    from . import oidn
    oidn.require()
    oidn.check_quality(args.denoise_quality)
    if args.ray is not None or args.resume:
        raise UsageError("--denoise renders locally: the denoiser needs the whole image in one process (no --ray)")
    if pixel_format != "rgb":
        raise UsageError(f"--denoise needs an rgb film, not '{pixel_format}'")
    if args.buffer and method != "expectation":
        raise UsageError("--buffer with --denoise image: the buffer keeps the expectation, which image denoising "
                         "leaves noisy; use --denoise expectation")
    if method == "expectation":
        from .coverage import check_k
        from .expectation import check_uncertainty
        check_k(coverage_of(args))
        check_uncertainty(uncertainty_of(args))
        from ..lookdev.commands import check_buffer_path
        from ..lookdev.record import check_film
        from . import expectation
        expectation.check(integrator)
        check_film(scene)  # the buffer's conditions: an rgb film, a filter it can record
        if args.buffer:
            check_buffer_path(args.buffer)


def coverage_of(args):
    """--coverage, "auto" when not given (`denoise.coverage`)."""
    value = getattr(args, "coverage", None)
    return "auto" if value is None else value


def uncertainty_of(args):
    """--denoise-uncertainty, the default when not given (`denoise.expectation.UNCERTAINTY`)."""
    from .expectation import UNCERTAINTY
    value = getattr(args, "denoise_uncertainty", None)
    return UNCERTAINTY if value is None else value


def render_denoised(args, scene, integrator, pixel_format: str) -> int:
    """Both methods: the passes with a progress bar and the command line's Ctrl-C handling (`_passes`), then the
    denoising of the finished passes, also after a stop."""
    precheck(args, scene, integrator, pixel_format)
    from ..images import save_safely
    from ..runtime import init
    from ..sizing import lanes_per_pass
    lanes = lanes_per_pass(init())[0]
    if args.denoise == "expectation":
        from ..lookdev.record import scene_label
        from . import expectation
        job = expectation.Job(scene, integrator, args.spp, args.seed, args.denoise_quality,
                              label=scene_label(args.scene), coverage=coverage_of(args),
                              uncertainty=uncertainty_of(args), lanes_per_pass=lanes, pass_spp=args.pass_spp)
        def source():
            return (prog for prog, _ in job.passes())

        def finish(prog):
            if job.buffer.spp < 1:
                return None
            image, buf = job.finish()
            out = save_safely(image, args.output, pixel_format,
                              expectation.aovs(buf, image) if integrator.settings.aovs else None)
            if args.buffer:
                buf.save(args.buffer)
            points = buf.header.get("denoise", {}).get("coverage")
            return out, (f"expectation, the style at {points} points per pixel" if points else
                         "expectation, the style at the camera samples")
    else:
        from ..pipeline.passes import passes
        from . import image as post

        def source():
            return passes(scene, integrator, args.spp, args.seed, lanes_per_pass=lanes, pass_spp=args.pass_spp)

        def finish(prog):
            if prog.spp_done < 1:
                return None
            image, _, errs = post.finish(scene, prog, args.seed, args.denoise_quality)
            return save_safely(image, args.output, pixel_format, errs), "image"
    status, out, how = _passes(args, scene, lanes, source(), finish, pixel_format)
    if status is not None:
        return status
    if not args.quiet:
        print(f"wrote {out} ({integrator.settings.style.describe()}, spp {args.spp}, denoised: {how})",
              file=sys.stderr)
    return 0 if out == args.output else 1


def _passes(args, scene, lanes: int, source, finish, pixel_format: str):
    """Run the passes of `source` as `styletrace render` does (`frontends.signals`: its progress bar and stops),
    then `finish(last progress)` -> (written path, how) or None where not every pixel has a pass yet. A stop
    (Ctrl-C, SIGTERM, an error in a later pass) finishes, that is denoises and writes, the finished passes (and
    --buffer); where the pass under way does not end within the grace period, the noisy finished passes are
    written instead (denoising needs the kernel under way to finish). Returns (exit status if stopped else None,
    the written path, how it was denoised)."""
    from ..frontends.signals import Passes, StopSignals, say
    from ..images import save_safely
    from ..pipeline.passes import pass_count
    run = Passes(args.spp, pass_count(scene, args.spp, lanes, pass_spp=args.pass_spp), args.quiet)

    def abandon(signum):  # from the watcher thread, the kernel still running: the noisy finished passes
        latest = run.latest
        if latest is None or latest.spp_done < 1:
            say("styletrace: interrupted before the first pass finished; nothing written")
        else:
            out = save_safely(latest.image[..., :3], args.output, pixel_format, None, plain=True)
            say(f"styletrace: interrupted; wrote {out} from {latest.spp_done} of {args.spp} spp, NOT denoised "
                f"(the pass under way did not end)")
        sys.stderr.flush()
        os._exit(128 + signum)

    with StopSignals(abandon) as stop:
        try:
            run.follow(source, stop)
        finally:
            run.close()
        with stop.lock:
            stop.settled = True
        latest, failure = run.latest, run.failure
        done = finish(latest) if latest is not None else None
        if done is None:
            if failure is not None:
                raise failure
            say("styletrace: interrupted before every pixel had a pass; nothing written")
            return stop.exit_status, None, None
        out, how = done
    if failure is not None or stop.count:
        what = f"error ({first_line(failure)})" if failure is not None else "interrupted"
        say(f"styletrace: {what} after {latest.spp_done} of {args.spp} spp; wrote the finished passes, denoised, "
            f"to {out}" + (f" and {args.buffer}" if args.buffer else ""))
        return (1 if failure is not None else stop.exit_status), out, how
    return None, out, how


__all__ = ["render_denoised"]
