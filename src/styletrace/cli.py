"""Command line: `styletrace render`, `styletrace styles`, `styletrace estimators`, `styletrace gallery`.

Every error a user can cause (unknown style or parameter, bad value, missing or broken scene,
unwritable output, malformed arguments) ends with one line on stderr and exit status 2. Flags override
the scene's own `stylized` integrator only where given. A failure after some passes still writes them. Ctrl-C during a multi-pass
render finishes the pass under way (a second Ctrl-C abandons it), writes the average of the finished
passes, then exits with status 130.
"""
from __future__ import annotations

import argparse
import os
import signal
import sys
from typing import Sequence

from .errors import StyletraceError, UsageError
from .images import IMAGE_TYPES, save_safely


def _parse_set(items: Sequence[str]) -> dict[str, str]:
    out = {}
    for item in items:
        if "=" not in item or not item.split("=", 1)[0].strip():
            raise UsageError(f"bad --set {item!r}: expected KEY=VALUE, e.g. --set threshold=0.6")
        key, value = item.split("=", 1)
        out[key.strip()] = value.strip()
    return out


def check_output(path: str) -> None:
    """Fail before rendering, not after, if the image could not be written."""
    ext = os.path.splitext(path)[1].lower()
    if ext not in IMAGE_TYPES:
        raise UsageError(f"bad output {path!r}: the extension must be one of {', '.join(IMAGE_TYPES)} "
                         f"(.exr is linear, .png is sRGB)")
    if os.path.isdir(path):
        raise UsageError(f"cannot write {path!r}: it is a folder")
    folder = os.path.dirname(os.path.abspath(path))
    if not os.path.isdir(folder):
        raise UsageError(f"cannot write {path!r}: folder {folder!r} does not exist")
    if not os.access(folder, os.W_OK) or (os.path.exists(path) and not os.access(path, os.W_OK)):
        raise UsageError(f"cannot write {path!r}: permission denied")


class InterruptFlag:
    """Ctrl-C handling for the pass loop: the first Ctrl-C finishes the pass under way, the second
    abandons it. Either way the passes already finished are written (an exception raised by a signal
    handler inside a running kernel would otherwise surface as an unrelated RuntimeError)."""

    def __enter__(self):
        self.count = 0
        self._old = signal.getsignal(signal.SIGINT)
        signal.signal(signal.SIGINT, self._handle)
        return self

    def _handle(self, signum, frame):
        self.count += 1
        if self.count == 1:
            print("\nstyletrace: stopping after this pass (Ctrl-C again to stop now)", file=sys.stderr)
        else:
            raise KeyboardInterrupt

    def __exit__(self, *exc):
        signal.signal(signal.SIGINT, self._old)
        return False


def cmd_styles(args) -> int:
    from .runtime import init
    init()
    from .plugins.estimation import applicable
    from .styles import get, names

    for name in names():
        cls = get(name)
        inner = "closed form, 0 samples" if cls.default_inner == 0 else f"default inner samples {cls.default_inner}"
        print(f"{name}: {cls.summary} [{inner}]")
        for p in cls.params:
            print(f"    {p.name} = {p.show(p.default)}    {p.explain()}; {p.allowed()}")
        print(f"    estimators: {', '.join(applicable(cls()))}")
    print("compositions: STYLE+STYLE[+...] applies the styles in order as one style, e.g. contrast+sepia; "
          "parameters are STYLE.PARAM (contrast.c=1.6); estimators: direct, or affine / combined / telescoping "
          "where every operand has a form (docs/styles.md#compositions)")
    return 0


def cmd_estimators(args) -> int:
    from .runtime import init
    init()
    from .plugins.estimation import kinds

    for k in kinds():
        print(f"{k.name}: {k.doc}")
        print(f"    forms: {k.describe_forms()}; inner_samples n: {k.inner}")
        for key, value in k.params.items():
            print(f"    {key} = {value}")
    return 0


def cmd_render(args) -> int:
    check_output(args.output)
    params = _parse_set(args.set)
    for flag, value in (("--width", args.width), ("--height", args.height), ("--spp", args.spp),
                        ("--pass-spp", args.pass_spp)):
        if value is not None and value < 1:
            raise UsageError(f"bad value {value} for {flag}: expected an integer >= 1")

    from . import api

    scene = api.load_scene(args.scene, args.width, args.height)
    integrator = choose_integrator(scene, args, params)
    integrator, chosen = api.resolve_defaults(scene, integrator)  # scene-relative defaults, printed to pin them
    if chosen and not args.quiet:
        print(f"styletrace: auto values: {chosen}", file=sys.stderr)

    lanes = api.LANES_PER_PASS
    if args.pass_spp:
        size = scene.sensors()[0].film().crop_size()
        lanes = args.pass_spp * int(size[0]) * int(size[1])
    total = api.pass_count(scene, args.spp, lanes)
    bar = None
    if total > 1 and not args.quiet:
        from tqdm import tqdm
        bar = tqdm(total=args.spp, unit="spp", desc="rendering", file=sys.stderr)
    latest, failure = None, None
    with InterruptFlag() as stop:
        try:
            for prog in api.passes(scene, integrator, args.spp, args.seed, lanes):
                if bar is not None:
                    bar.update(prog.spp_done - (latest.spp_done if latest else 0))
                latest = prog
                if stop.count:
                    break
        except (KeyboardInterrupt, RuntimeError) as exc:
            # A second Ctrl-C abandons the pass under way (Dr.Jit may wrap it in a RuntimeError); any other
            # failure of a later pass must not cost the passes already finished.
            if not stop.count and latest is None:
                raise
            failure = None if stop.count else exc
    if bar is not None:
        bar.close()
    if failure is not None:
        out = save_safely(latest.image, args.output)
        print(f"styletrace: error after {latest.spp_done} of {args.spp} spp ({api.first_line(failure)}); wrote the "
              f"finished passes to {out}", file=sys.stderr)
        return 1
    if stop.count:
        if latest is None:
            print("styletrace: interrupted before the first pass finished; nothing written", file=sys.stderr)
            return 130
        out = save_safely(latest.image, args.output)
        print(f"styletrace: interrupted; wrote {out} from {latest.spp_done} of {args.spp} spp", file=sys.stderr)
        return 130
    out = save_safely(latest.image, args.output)
    if not args.quiet:
        import mitsuba as mi
        print(f"wrote {out} ({mi.variant()}, {integrator.settings.style.describe()}, spp {args.spp})",
              file=sys.stderr)
    return 0 if out == args.output else 1


def choose_integrator(scene, args, params):
    """The scene's own `stylized` integrator with the flags and --set values the user gave applied on top
    (a scene without one starts from the command line's default style)."""
    from .plugins import settings
    from .plugins.integrator import StylizedIntegrator

    own = scene.integrator()
    given = {p.name: getattr(args, p.name) for p in settings.PROPERTIES if getattr(args, p.name) is not None}
    given.update(params)
    if isinstance(own, StylizedIntegrator):
        if not given:
            return own
        base = own.values
    else:
        base = {"style": settings.COMMAND_LINE_STYLE}
    return StylizedIntegrator.from_values(settings.refine(base, given))


def cmd_gallery(args) -> int:
    from . import gallery

    opts = gallery.QUICK if args.quick else gallery.Options()
    if args.size:
        opts.size = args.size
    if os.path.exists(args.output) and not os.path.isdir(args.output):
        raise UsageError(f"bad output {args.output!r}: expected a folder")
    only = [k.strip() for k in args.only.split(",")] if args.only else None
    try:
        res = gallery.run(args.output, opts, only, log=lambda m: print(m, file=sys.stderr))
    except ValueError as exc:
        raise UsageError(str(exc)) from None
    print(f"wrote {os.path.join(args.output, 'index.html')} ({len(res['setups'])} setups, {res['seconds']:.0f} s)",
          file=sys.stderr)
    return 0


class Parser(argparse.ArgumentParser):
    """argparse with the project's error format: one line, exit status 2 (no usage dump)."""

    def error(self, message):
        self.exit(2, f"styletrace: error: {message} (see '{self.prog} --help')\n")


def build_parser() -> argparse.ArgumentParser:
    p = Parser(prog="styletrace", description="Stylized global illumination as a function of expectation.")
    sub = p.add_subparsers(dest="command", required=True)

    r = sub.add_parser("render", help="render a scene with a style")
    r.add_argument("scene", nargs="?", default="cornell-box",
                   help="built-in scene (cornell-box, dragon, mixed, furnace) or a Mitsuba XML file "
                        "(default: cornell-box)")
    r.add_argument("--set", action="append", default=[], metavar="KEY=VALUE", help="a style or integrator parameter")
    add_setting_flags(r)
    r.add_argument("--spp", type=int, default=16, help="camera samples per pixel (default 16)")
    r.add_argument("--width", type=int, default=None, help="image width (built-in scenes; XML with $resx)")
    r.add_argument("--height", type=int, default=None, help="image height (built-in scenes; XML with $resy)")
    r.add_argument("--seed", type=int, default=0, help="random seed; the same seed gives the same image")
    r.add_argument("--pass-spp", type=int, default=None, help="samples per pixel per pass (default: by memory)")
    r.add_argument("-o", "--output", default="render.png", help="output image: .exr (linear) or .png (sRGB)")
    r.add_argument("-q", "--quiet", action="store_true", help="no progress bar or summary")
    r.set_defaults(func=cmd_render)

    g = sub.add_parser("gallery", help="reproduce the paper's result setups on the dragon scene")
    g.add_argument("-o", "--output", default="gallery", help="output folder (default: gallery)")
    g.add_argument("--quick", action="store_true", help="small and fast (under a minute)")
    g.add_argument("--size", type=int, default=None, help="image size in pixels (square)")
    g.add_argument("--only", default=None, help="comma-separated setup keys to run")
    g.set_defaults(func=cmd_gallery)

    s = sub.add_parser("styles", help="list the styles and their parameters")
    s.set_defaults(func=cmd_styles)
    e = sub.add_parser("estimators", help="list the estimators of g(E[L]) and the forms they need")
    e.set_defaults(func=cmd_estimators)
    return p


def add_setting_flags(parser) -> None:
    """One flag per integrator property that has one; help and defaults come from the settings table."""
    from .plugins import settings
    for p in settings.PROPERTIES:
        if not p.flag:
            continue
        default = f"the scene's stylized integrator's, else {settings.COMMAND_LINE_STYLE}" if p.name == "style" \
            else p.show_default()
        parser.add_argument(p.flag, dest=p.name, default=None, metavar=p.metavar,
                            type=int if p.kind == "int" else str, help=f"{p.doc} (default: {default})")


def main(argv: Sequence[str] | None = None) -> int:
    try:
        # the flags' help comes from the settings table, which needs the backend: errors there are one line too
        args = build_parser().parse_args(argv)
        return args.func(args)
    except KeyboardInterrupt:
        print("styletrace: interrupted", file=sys.stderr)
        return 130
    except StyletraceError as exc:
        print(f"styletrace: error: {exc}", file=sys.stderr)
        return 2


if __name__ == "__main__":
    sys.exit(main())
