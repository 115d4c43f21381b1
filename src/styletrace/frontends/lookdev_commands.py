"""Command line of look development: `render --buffer`, `restyle`, `fit`, `preview`.

    styletrace render dragon --style cel --spp 16 --buffer dragon.npz -o dragon.png
    styletrace restyle dragon.npz --style color_map --set gradient=heat -o heat.png
    styletrace fit dragon.npz --style cel --target look.png -o fitted.png
    styletrace preview dragon --port 8765

`render --buffer` runs through the pipeline's runner with `lookdev.record.Recorded`
(`denoise.finishers.plan`). `cli.build_parser` calls `add_parsers`, handing over its own
helpers (so this module never imports `cli`); nothing here loads Dr.Jit or Mitsuba before a
command runs.
"""
from __future__ import annotations

import sys
from functools import partial

from styletrace.errors import UsageError

#: `--buffer`'s help: the sizes a user sees (tests/lookdev/test_commands.py measures them)
BUFFER_HELP = (
    "also write the expectation buffer (.npz) for `styletrace restyle`/`fit`. Denoised (as at the "
    "defaults) it holds the denoised expectation at the --coverage points, 65 bytes each: 64 per "
    "pixel (4.2 kB a pixel: 69.7 MB at 128x128), fewer where they would pass 4194304 points "
    "(about 274 MB from 256x256 up). Not denoised, it holds the camera samples: 65 bytes each (81 "
    "with first_object_hit; 77 with --coverage 0, which keeps them denoised), at most 4194304 "
    "(512x512 at 16 spp); with an unbiased estimator (series*, ustat, naive, telescoping, "
    "combined) it stores each sample's children and uniforms: at most 1048576 camera samples and "
    "64 children per sample on average, 57 bytes + 13 per child + 5 per uniform each. Each file "
    "adds the pilot's 1.5 MiB"
)


def cmd_restyle(args, parse_set, check_output) -> int:
    """`styletrace restyle`: a buffer restyled without tracing, written to the output.

    Args:
        args: the parsed arguments (buffer, style, estimator, set, output).
        parse_set, check_output: the command line's --set parser and output check.

    Returns:
        The exit status, 0.
    """
    check_output(args.output)
    params = parse_set(args.set)
    from styletrace.images import write_image
    from styletrace.lookdev.buffer import load_buffer
    from styletrace.lookdev.restyle import restyle

    img = restyle(load_buffer(args.buffer), style=args.style, estimator=args.estimator, **params)
    write_atomically(img, args.output, write_image)
    print(f"wrote {args.output}", file=sys.stderr)
    return 0


def write_atomically(img, path: str, write_image) -> None:
    """Write an image: `images.write_image` is atomic itself (temporary file beside the target,
    fsync, rename) and writes through a symbolic link instead of replacing it.

    Args:
        img: the image. path: the target. write_image: the writer (`images.write_image`).
    """
    write_image(img, path)


def cmd_fit(args, parse_set, check_output) -> int:
    """`styletrace fit`: a style's parameters fitted so that the restyled buffer matches a target.

    Prints the fit's numbers and the `styletrace restyle` command of the fitted values.

    Args:
        args: the parsed arguments (buffer, style, target, set, fix, iterations, lr, output).
        parse_set, check_output: the command line's --set parser and output check.

    Returns:
        The exit status, 0.
    """
    if args.output:
        check_output(args.output)
    initial = parse_set(args.set)
    fixed = tuple(k.strip() for k in args.fix.split(",") if k.strip()) if args.fix else ()
    from styletrace.images import write_image
    from styletrace.lookdev.buffer import load_buffer
    from styletrace.lookdev.fit import fit
    from styletrace.styles import style_class

    buf = load_buffer(args.buffer)
    style = args.style or buf.header["slots"][0]["style"]
    result = fit(
        buf,
        style=style,
        target=args.target,
        iterations=args.iterations,
        lr=args.lr,
        fixed=fixed,
        **initial,
    )
    import shlex
    params = {p.name: p for p in style_class(style).params}
    shown = {k: v for k, v in initial.items() if k not in result.params}
    shown.update({k: params[k].show(v) for k, v in result.params.items()})
    print(
        f"fitted in {result.iterations} iterations ({result.seconds:.2f} s), mean squared error "
        f"{result.loss:.3g}"
    )
    print(shlex.join(["styletrace", "restyle", args.buffer, "--style", style]
                     + [w for k, v in shown.items() for w in ("--set", f"{k}={v}")]))
    if args.output:
        write_atomically(result.image, args.output, write_image)
        print(f"wrote {args.output}", file=sys.stderr)
    return 0


def cmd_preview(args, parse_set) -> int:
    """`styletrace preview`: serve the preview page until Ctrl-C.

    Args:
        args: the parsed arguments (scene, port, style, set, samples, inner, spp, width,
            height, seed, denoise).
        parse_set: the command line's --set parser.

    Returns:
        The exit status, 0.

    Raises:
        UsageError: a port outside 0..65535, or a size or count below 1.
    """
    params = parse_set(args.set)
    if not 0 <= args.port < 65536:
        raise UsageError(f"bad value {args.port} for --port: expected 0..65535")
    from styletrace.pipeline.job import check_counts
    check_counts(("--width", args.width), ("--height", args.height), ("--spp", args.spp),
                 ("--samples", args.samples), ("--inner", args.inner))
    from styletrace.preview.jobs import page_job
    from styletrace.preview.server import serve
    job = page_job(args.scene, style=args.style, params=params, samples=args.samples,
                   spp=args.spp, inner=args.inner, width=args.width, height=args.height,
                   seed=args.seed, denoise=args.denoise)
    return serve(job, port=args.port)


def add_parsers(sub, parse_set, check_output) -> None:
    """Add the `restyle`, `fit` and `preview` subcommands.

    Args:
        sub: the command line's subparsers. parse_set, check_output: its --set parser and output
            check, handed over so that this module never imports `cli`.
    """
    r = sub.add_parser(
        "restyle", help="restyle an expectation buffer (from render --buffer) without tracing"
    )
    r.add_argument("buffer", help="buffer file (.npz) written by `styletrace render --buffer`")
    r.add_argument("--style", default=None, help="new style (default: the recorded one)")
    r.add_argument(
        "--estimator",
        default=None,
        help="direct or affine on a buffer of means; on a buffer recorded with an unbiased "
        "estimator, any estimator whose requests the stored children and uniforms cover (refused "
        "otherwise) (default: the recorded one where it applies)",
    )
    r.add_argument(
        "--set", action="append", default=[], metavar="KEY=VALUE", help="a style parameter"
    )
    r.add_argument(
        "-o", "--output", default="restyle.png", help="output image: .exr (linear) or .png (sRGB)"
    )
    r.set_defaults(func=partial(cmd_restyle, parse_set=parse_set, check_output=check_output))

    f = sub.add_parser(
        "fit", help="fit a style's parameters so the restyled buffer matches a target image"
    )
    f.add_argument("buffer", help="buffer file (.npz) written by `styletrace render --buffer`")
    f.add_argument("--style", default=None, help="style to fit (default: the recorded one)")
    f.add_argument(
        "--target", required=True, help="target image, the buffer's size (.exr linear, .png sRGB)"
    )
    f.add_argument(
        "--set", action="append", default=[], metavar="KEY=VALUE", help="a starting value"
    )
    f.add_argument(
        "--fix", default=None, metavar="K1,K2", help="parameters to keep at their starting values"
    )
    f.add_argument("--iterations", type=int, default=300, help="most gradient steps (default 300)")
    f.add_argument("--lr", type=float, default=0.1, help="Adam's first learning rate (default 0.1)")
    f.add_argument(
        "-o", "--output", default=None, help="also write the fitted restyle (.exr or .png)"
    )
    f.set_defaults(func=partial(cmd_fit, parse_set=parse_set, check_output=check_output))

    p = sub.add_parser(
        "preview", help="tune a style live in the browser (serves http://127.0.0.1:PORT)"
    )
    p.add_argument(
        "scene", nargs="?", default="cornell-box", help="built-in scene or Mitsuba XML file"
    )
    p.add_argument(
        "--port",
        type=int,
        default=8765,
        help="port on 127.0.0.1 (default 8765; 0 picks a free one)",
    )
    p.add_argument("--style", default="cel", help="style to start with (default cel)")
    p.add_argument(
        "--set", action="append", default=[], metavar="KEY=VALUE", help="a starting style parameter"
    )
    p.add_argument(
        "--samples",
        type=int,
        default=None,
        metavar="N",
        help="paths per pixel to refine to, split into camera samples x children for the starting "
        "style as `render --samples` (default: the scene's sample count; 16 for built-in scenes)",
    )
    p.add_argument("--inner", type=int, default=None,
                   help="children per camera sample (default: from --samples)")
    p.add_argument("--spp", type=int, default=None,
                   help="camera samples per pixel to refine to (default: from --samples)")
    p.add_argument("--width", type=int, default=None, help="image width (default 256)")
    p.add_argument("--height", type=int, default=None, help="image height (default 256)")
    p.add_argument("--seed", type=int, default=0, help="the render's seed (default 0)")
    p.add_argument("--denoise", choices=("auto", "expectation", "image", "off"), default=None,
                   help="as `render --denoise` (default: auto, or $STYLETRACE_DENOISE)")
    p.set_defaults(func=partial(cmd_preview, parse_set=parse_set))


__all__ = ["add_parsers", "BUFFER_HELP"]
