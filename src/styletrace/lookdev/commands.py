"""Command line of look development: `render --buffer`, `restyle`, `fit`, `preview`.

    styletrace render dragon --style cel --spp 16 --buffer dragon.npz -o dragon.png
    styletrace restyle dragon.npz --style color_map --set gradient=heat -o heat.png
    styletrace fit dragon.npz --style cel --target look.png -o fitted.png
    styletrace preview dragon --port 8765

`cli.build_parser` calls `add_parsers`, handing over its own helpers (so this module never imports
`cli`); nothing here loads Dr.Jit or Mitsuba before a command runs.
"""
from __future__ import annotations

import os
import sys
from functools import partial

from ..errors import UsageError

BUFFER_HELP = (
    "also write the expectation buffer (.npz) for `styletrace restyle`/`fit`/`preview`; at most "
    "4194304 camera samples (512x512 at 16 spp), 65 bytes each (81 with first_object_hit); with an "
    "unbiased estimator (series*, ustat, naive, telescoping, combined) it stores each sample's "
    "children and uniforms: at most 1048576 camera samples and 64 children per sample on average, "
    "57 bytes + 13 per child + 5 per uniform each"
)


def check_buffer_path(path: str) -> None:
    if not path.lower().endswith(".npz"):
        raise UsageError(f"bad buffer file {path!r}: the extension must be .npz")
    from ..images import check_target
    check_target(path)  # before the render: the buffer is written after it


def render_with_buffer(args, scene, integrator, lanes: int | None = None, pilot=None) -> int:
    """`styletrace render ... --buffer FILE`: the render, and the buffer of every finished pass
    (`lanes`: camera samples per pass, the render pipeline's for this device, so the image is the
    plain render's; `pilot`: the scene-defaults pilot the auto values were resolved with, which
    record stores rather than tracing anew)."""
    check_buffer_path(args.buffer)
    from .. import api
    from ..images import save_safely
    from .record import record, scene_label

    latest = buf = None
    failure = None
    try:
        kw = {} if lanes is None else {"lanes_per_pass": lanes}
        for latest, buf in record(scene, integrator, args.spp, args.seed, scene_label(args.scene), pilot=pilot, **kw):
            pass
    except (KeyboardInterrupt, RuntimeError) as exc:  # keep the finished passes (see cli.cmd_render)
        if latest is None:
            raise
        failure = exc
    out = save_safely(latest.image, args.output)
    buf.save(args.buffer)
    if failure is not None:
        what = "interrupted" if isinstance(failure, KeyboardInterrupt) else f"error ({api.first_line(failure)})"
        print(
            f"styletrace: {what} after {latest.spp_done} of {args.spp} spp; wrote the finished "
            f"passes to {out} and {args.buffer}",
            file=sys.stderr,
        )
        return 130 if isinstance(failure, KeyboardInterrupt) else 1
    if not args.quiet:
        print(
            f"wrote {out} and {args.buffer} ({buf.samples} camera samples, "
            f"{buf.nbytes / 2**20:.1f} MiB)",
            file=sys.stderr,
        )
    return 0 if out == args.output else 1


def cmd_restyle(args, parse_set, check_output) -> int:
    check_output(args.output)
    params = parse_set(args.set)
    from ..images import write_image
    from .buffer import load_buffer
    from .restyle import restyle

    img = restyle(load_buffer(args.buffer), style=args.style, estimator=args.estimator, **params)
    write_atomically(img, args.output, write_image)
    print(f"wrote {args.output}", file=sys.stderr)
    return 0


def write_atomically(img, path: str, write_image) -> None:
    """Write an image: `images.write_image` is atomic itself (temporary file beside the target,
    fsync, rename) and writes through a symbolic link instead of replacing it."""
    write_image(img, path)


def cmd_fit(args, parse_set, check_output) -> int:
    if args.output:
        check_output(args.output)
    initial = parse_set(args.set)
    fixed = tuple(k.strip() for k in args.fix.split(",") if k.strip()) if args.fix else ()
    from ..images import write_image
    from ..styles import get
    from .buffer import load_buffer
    from .fit import fit

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
    params = {p.name: p for p in get(style).params}
    shown = {k: v for k, v in initial.items() if k not in result.params}
    shown.update({k: params[k].show(v) for k, v in result.params.items()})
    print(f"fitted in {result.iterations} iterations ({result.seconds:.2f} s), mean squared error "
          f"{result.loss:.3g}")
    print(shlex.join(["styletrace", "restyle", args.buffer, "--style", style]
                     + [w for k, v in shown.items() for w in ("--set", f"{k}={v}")]))
    if args.output:
        write_atomically(result.image, args.output, write_image)
        print(f"wrote {args.output}", file=sys.stderr)
    return 0


def cmd_preview(args, parse_set) -> int:
    params = parse_set(args.set)
    if not 0 <= args.port < 65536:
        raise UsageError(f"bad value {args.port} for --port: expected 0..65535")
    for flag, value in (("--width", args.width), ("--height", args.height), ("--spp", args.spp)):
        if value is not None and value < 1:
            raise UsageError(f"bad value {value} for {flag}: expected an integer >= 1")
    from ..preview.server import serve
    return serve(args.scene, style=args.style, inner=args.inner, spp=args.spp, width=args.width,
                 height=args.height, port=args.port, params=params, open_browser=False)


def add_parsers(sub, parse_set, check_output) -> None:
    r = sub.add_parser("restyle", help="restyle an expectation buffer (from render --buffer) "
                                       "without tracing")
    r.add_argument("buffer", help="buffer file (.npz) written by `styletrace render --buffer`")
    r.add_argument("--style", default=None, help="new style (default: the recorded one)")
    r.add_argument(
        "--estimator",
        default=None,
        help="direct or affine on a buffer of means; on a buffer recorded with an unbiased "
        "estimator, any estimator whose requests the stored children and uniforms cover (refused "
        "otherwise) (default: the recorded one where it applies)",
    )
    r.add_argument("--set", action="append", default=[], metavar="KEY=VALUE", help="a style parameter")
    r.add_argument("-o", "--output", default="restyle.png", help="output image: .exr (linear) or "
            ".png (sRGB)")
    r.set_defaults(func=partial(cmd_restyle, parse_set=parse_set, check_output=check_output))

    f = sub.add_parser("fit", help="fit a style's parameters so the restyled buffer matches a "
                                   "target image")
    f.add_argument("buffer", help="buffer file (.npz) written by `styletrace render --buffer`")
    f.add_argument("--style", default=None, help="style to fit (default: the recorded one)")
    f.add_argument("--target", required=True, help="target image, the buffer's size (.exr linear, "
                                                   ".png sRGB)")
    f.add_argument("--set", action="append", default=[], metavar="KEY=VALUE", help="a starting value")
    f.add_argument("--fix", default=None, metavar="K1,K2", help="parameters to keep at their "
            "starting values")
    f.add_argument("--iterations", type=int, default=300, help="most gradient steps (default 300)")
    f.add_argument("--lr", type=float, default=0.1, help="Adam's first learning rate (default 0.1)")
    f.add_argument("-o", "--output", default=None, help="also write the fitted restyle (.exr or "
                                                        ".png)")
    f.set_defaults(func=partial(cmd_fit, parse_set=parse_set, check_output=check_output))

    p = sub.add_parser("preview", help="tune a style live in the browser (serves "
                                       "http://127.0.0.1:PORT)")
    p.add_argument("scene", nargs="?", default="cornell-box", help="built-in scene or Mitsuba XML "
            "file")
    p.add_argument("--port", type=int, default=8765, help="port on 127.0.0.1 (default 8765; 0 "
                                                          "picks a free one)")
    p.add_argument("--style", default="cel", help="style to start with (default cel)")
    p.add_argument("--set", action="append", default=[], metavar="KEY=VALUE", help="a starting style parameter")
    p.add_argument("--inner", type=int, default=None, help="children per camera sample (default 8)")
    p.add_argument("--spp", type=int, default=None, help="camera samples per pixel to refine to "
                                                         "(default 16)")
    p.add_argument("--width", type=int, default=None, help="image width (default 256)")
    p.add_argument("--height", type=int, default=None, help="image height (default 256)")
    p.set_defaults(func=partial(cmd_preview, parse_set=parse_set))


__all__ = ["add_parsers", "render_with_buffer", "BUFFER_HELP"]
