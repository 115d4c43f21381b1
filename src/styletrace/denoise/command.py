"""`styletrace render --denoise expectation|image [--denoise-quality high] [--coverage K] [--buffer FILE]`.

`cli.cmd_render` hands over here after it has loaded the scene, built the integrator and pinned its `auto`
values (so `--denoise` refuses, in one line and with exit status 2, before anything renders). The output is
written atomically (`images.save_safely`); with `--aovs` the EXR gets the honest channels of
`denoise.expectation.aovs` / `denoise.image.render`; with `--buffer` (expectation only) the buffer keeps the
denoised expectation, so `styletrace restyle` styles it.
"""
from __future__ import annotations

import sys

from ..errors import UsageError
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
        check_film(scene)  # the buffer's conditions: box filter, no border sampling
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
    precheck(args, scene, integrator, pixel_format)
    method = args.denoise
    how = method
    from ..images import save_safely
    if method == "expectation":
        from ..lookdev.record import scene_label
        from . import expectation
        image, buf = expectation.render(scene, integrator, args.spp, args.seed, args.denoise_quality,
                                        label=scene_label(args.scene), coverage=coverage_of(args),
                                        uncertainty=uncertainty_of(args))
        errs = expectation.aovs(buf, image) if integrator.settings.aovs else None
        out = save_safely(image, args.output, pixel_format, errs)
        if args.buffer:
            buf.save(args.buffer)
        points = buf.header.get("denoise", {}).get("coverage")
        how += f", the style at {points} points per pixel" if points else ", the style at the camera samples"
    else:
        from ..runtime import init
        from ..sizing import lanes_per_pass
        from . import image as post
        image, _, errs = post.render(scene, integrator, args.spp, args.seed, args.denoise_quality,
                                     lanes_per_pass=lanes_per_pass(init())[0], pass_spp=args.pass_spp)
        out = save_safely(image, args.output, pixel_format, errs)
    if not args.quiet:
        print(f"wrote {out} ({integrator.settings.style.describe()}, spp {args.spp}, denoised: {how})",
              file=sys.stderr)
    return 0 if out == args.output else 1


__all__ = ["render_denoised"]
