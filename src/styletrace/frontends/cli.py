"""Command line: `styletrace render`, `styletrace styles`, `styletrace estimators`,
`styletrace gallery`.

Every error a user can cause (unknown style or parameter, bad value, missing or broken scene,
unwritable output, an image too large for memory, malformed arguments) ends with one line on stderr
(newlines in names are escaped) and exit status 2. Flags override the scene's own `stylized`
integrator only where given. A failure after some passes still writes them. Ctrl-C or SIGTERM during
a render stops after the pass under way, or within `StopSignals.GRACE` seconds if that pass takes
longer (a second signal: at once); the average of the finished passes is written, then the exit
status is 130 (Ctrl-C) or 143 (SIGTERM). A wait of more than two seconds (loading the scene, the
auto values' pilot, the first pass with its kernel compilation) names itself on a stderr status line
(`status.py`).
"""
from __future__ import annotations

import argparse
import os
import re
import sys
import warnings
from typing import Mapping, Sequence

from styletrace.config.choices import SAMPLERS
from styletrace.errors import StyletraceError, UsageError
from styletrace.frontends.status import Status
from styletrace.images import IMAGE_TYPES, check_target
from styletrace.pipeline.job import check_counts
from styletrace.pipeline.signals import StopSignals, one_line, say  # noqa: F401  (StopSignals: tests import it here)


def _parse_defines(items: Sequence[str]) -> dict[str, str]:
    """`-D NAME=VALUE` (repeatable): values of the scene file's <default> parameters, as Mitsuba's
    own -D."""
    out = {}
    for item in items:
        key, eq, value = item.partition("=")
        if not eq or not key.strip().isidentifier():
            raise UsageError(
                f"bad -D {item!r}: expected NAME=VALUE for a <default name=\"NAME\"> of the scene, "
                f"e.g. -D spp=64"
            )
        out[key.strip()] = value.strip()
    return out


def _parse_set(items: Sequence[str]) -> dict[str, str]:
    out = {}
    for item in items:
        if "=" not in item or not item.split("=", 1)[0].strip():
            raise UsageError(f"bad --set {item!r}: expected KEY=VALUE, e.g. --set threshold=0.6")
        key, value = item.split("=", 1)
        out[key.strip()] = value.strip()
    return out


def check_output(path: str, scene: str | None = None) -> None:
    """Fail before rendering, not after, if the image could not be written or would overwrite the
    scene.

    Args:
        path: the output image. scene: the scene argument (None: none to compare with).

    Raises:
        UsageError: the scene's own file, an extension not in IMAGE_TYPES, or a target that
            cannot be written (`images.check_target`).
    """
    if (
        scene is not None
        and os.path.exists(scene)
        and os.path.exists(path)
        and os.path.samefile(scene, path)
        or scene is not None
        and os.path.realpath(scene) == os.path.realpath(path)
    ):
        raise UsageError(f"bad output {path!r}: it is the scene file being rendered")
    ext = os.path.splitext(path)[1].lower()
    if ext not in IMAGE_TYPES:
        raise UsageError(
            f"bad output {path!r}: the extension must be one of {', '.join(IMAGE_TYPES)} "
            f"(.exr is linear, .png is sRGB)"
        )
    check_target(path)


def cmd_styles(args) -> int:
    """`styletrace styles`: every style, its parameters and estimators, on stdout.

    Args:
        args: the parsed arguments (none used).

    Returns:
        The exit status, 0.
    """
    from styletrace.scene.plugins import init
    init()
    from styletrace.config.estimator_registry import applicable
    from styletrace.styles import style_class, style_names

    for name in style_names():
        cls = style_class(name)
        inner = (
            "closed form, 0 samples"
            if cls.default_inner == 0
            else f"default inner samples {cls.default_inner}"
        )
        print(f"{name}: {cls.summary} [{inner}]")
        for p in cls.params:
            print(f"    {p.name} = {p.show(p.default)}    {p.explain()}; {p.allowed()}")
        print(f"    estimators: {', '.join(applicable(cls()))}")
    print(
        "compositions: STYLE+STYLE[+...] applies the styles in order as one style, e.g. "
        "contrast+sepia; parameters are STYLE.PARAM (contrast.c=1.6); estimators: direct, or "
        "affine / combined / telescoping where every operand has a form "
        "(docs/styles.md#compositions)"
    )
    print("feature lines: any style with --lines (`styletrace lines` lists their settings)")
    return 0


def cmd_lines(args) -> int:
    """`styletrace lines`: the feature line settings, on stdout.

    Args:
        args: the parsed arguments (none used).

    Returns:
        The exit status, 0.
    """
    from styletrace.scene.plugins import init
    init()
    from styletrace.config import settings

    print(
        "feature lines (West 2021) on path edges, with any style and stylize mode: `render "
        "--lines` and `--set NAME=VALUE` (Python: styletrace.render(..., lines=True, "
        "line_width=2)); docs/lines.md"
    )
    for p in settings.PROPERTIES:
        if p.name == "lines" or p.name.startswith("line_"):
            print(f"    {p.name} = {p.show_default()}    {p.doc}")
    return 0


def cmd_estimators(args) -> int:
    """`styletrace estimators`: every estimator, its forms and parameters, on stdout.

    Args:
        args: the parsed arguments (none used).

    Returns:
        The exit status, 0.
    """
    from styletrace.scene.plugins import init
    init()
    from styletrace.config.estimator_registry import kinds

    for k in kinds():
        print(f"{k.name}: {k.doc}")
        print(f"    forms: {k.describe_forms()}; inner_samples n: {k.inner}")
        for key, value in k.params.items():
            print(f"    {key} = {value}")
    return 0


def cmd_render(args) -> int:
    """`styletrace render`: the flags as a job, an executor and a finisher that a runner runs.

    Args:
        args: the parsed arguments of `styletrace render`.

    Returns:
        The exit status (`pipeline.runner.Runner.write`; several scenes or frames:
        `ray_command.frames_command`).

    Raises:
        UsageError: flags that do not go together (--coverage or --denoise-uncertainty without
            expectation), bad values, or a refusal of the run (one line).
    """
    from styletrace.frontends.command_job import denoising_of, job_of
    method = denoising_of(args).method
    if args.denoise_uncertainty is not None and method not in ("expectation", "auto"):
        raise UsageError(
            f"--denoise-uncertainty {args.denoise_uncertainty} applies to --denoise expectation "
            "only"
        )
    if args.coverage is not None and method not in ("expectation", "auto"):
        raise UsageError(
            f"--coverage {args.coverage} applies to --denoise expectation only (the points where "
            "the style meets the denoised expectation)"
        )
    several = len(args.scene) > 1 or args.frames is not None or args.orbit is not None
    if several:  # numbered images in chunks: here, or each chunk a Ray task of the same pipeline
        from styletrace.frontends.ray_command import frames_command
        return frames_command(args, _parse_set, _parse_defines, check_output, say)
    scene = args.scene[0] if args.scene else "cornell-box"
    check_output(args.output, scene)
    params = _parse_set(args.set)
    check_counts(("--width", args.width), ("--height", args.height), ("--spp", args.spp),
                 ("--samples", args.samples), ("--pass-spp", args.pass_spp))
    from styletrace.frontends.ray_command import executor_of
    from styletrace.pipeline.runner import Voice
    status = Status(enabled=not args.quiet)
    runner = plan_with_status(job_of(args, params, _parse_defines(args.define), scene=scene),
                              executor_of(args), args.buffer, status)
    if runner.resolved.note and not args.quiet:
        say(f"styletrace: {runner.resolved.note}")
    return runner.write(args.output, Voice(args.quiet, status))


def plan_with_status(job, executor, buffer, status):
    """The job's run (`denoise.finishers.plan`), its long phases named on the status line.

    Args:
        job: the `pipeline.job.Job`. executor: where its passes run. buffer: a file for the
            expectation buffer, or None. status: the `status.Status` line.

    Returns:
        The `pipeline.runner.Runner`; the scene's warnings have been said, one line each.
    """
    from styletrace.jit import backend
    # Dr.Jit picks its libLLVM when first imported: choose it (and the variant) before that
    backend()
    from styletrace.denoise.finishers import Recording, plan
    from styletrace.scene.loading import SceneWarning
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", SceneWarning)
        with status.phase(f"loading scene {one_line(job.scene or 'cornell-box')}"):
            loaded = job.load()
        with status.phase(
            "measuring the scene for its auto values: compiling and rendering a pilot"
        ):
            runner = plan(job, executor, loaded, Recording(path=buffer))
        del loaded
    for w in caught:
        say(f"styletrace: warning: {w.message}")
    return runner


def cli_integrator(scene, args, params):
    """The scene's own `stylized` integrator with the flags and --set values the user gave applied
    on top: `pipeline.resolve.choose_integrator`'s.

    A scene without one starts from the command line's default style and keeps the max_depth,
    rr_depth and hide_emitters of its own Mitsuba integrator, unless a flag says otherwise.

    Args:
        scene: the loaded scene. args: the parsed arguments (flags, -D). params: the --set values.

    Returns:
        The integrator, its `auto` values not yet pinned.
    """
    from styletrace.frontends.command_job import job_of
    from styletrace.pipeline.resolve import choose_integrator as choose
    return choose(scene, job_of(args, params, _parse_defines(getattr(args, "define", []) or [])))


def cmd_gallery(args) -> int:
    """`styletrace gallery`: the paper's result setups and the equal-time section, into a folder.

    Args:
        args: the parsed arguments (output, quick, size, only, skip).

    Returns:
        The exit status, 0.

    Raises:
        UsageError: an unknown setup key or an unusable folder. StyletraceError: a refused setting.
    """
    from styletrace.frontends import gallery

    opts = gallery.QUICK if args.quick else gallery.Options()
    if args.size:
        opts.size = opts.equal_time_size = args.size
    only = [k.strip() for k in args.only.split(",")] if args.only else None
    skip = [k.strip() for k in args.skip.split(",")] if args.skip else None
    try:
        gallery.select_setups(only, skip)  # unknown keys fail here, before the folder is made
    except ValueError as exc:
        raise UsageError(str(exc)) from None
    check_gallery_folder(args.output)
    try:
        res = gallery.run_gallery(args.output, opts, only, log=say, skip=skip)
    except ValueError as exc:
        raise UsageError(str(exc)) from None
    say(f"wrote {os.path.join(args.output, 'index.html')} ({len(res['setups'])} setups, "
        f"{len(res['equal_time'])} equal-time comparisons, {res['seconds']:.0f} s)")
    return 0


def check_gallery_folder(path: str) -> None:
    """The gallery's folder: existing and writable, or created now (its parent must exist, as for
    `render`'s output): a failure comes before rendering, not after.

    Args:
        path: the folder.

    Raises:
        UsageError: not a folder, not writable (a file cannot be made in it: /sys as root too), or
            it cannot be created.
    """
    if os.path.exists(path):
        if not os.path.isdir(path):
            raise UsageError(f"bad output {path!r}: expected a folder")
        if not os.access(path, os.W_OK):
            raise UsageError(f"cannot write into {path!r}: permission denied")
        from styletrace.images import check_folder_takes_files
        check_folder_takes_files(path, path)
        return
    parent = os.path.dirname(os.path.abspath(path))
    if not os.path.isdir(parent):
        raise UsageError(f"cannot create {path!r}: folder {parent!r} does not exist")
    try:
        os.mkdir(path)
    except OSError as exc:
        raise UsageError(f"cannot create {path!r}: {exc.strerror}") from None


class Parser(argparse.ArgumentParser):
    """argparse with the project's error format: one line, exit status 2 (no usage dump)."""

    def error(self, message):
        """Exit with the project's one-line error (status 2, no usage dump).

        Args:
            message: argparse's message.
        """
        self.exit(2, one_line(f"styletrace: error: {message} (see '{self.prog} --help')") + "\n")


def builtin_scenes() -> str:
    """The built-in scenes' names for a help text, from the one registry
    (`scene.builtin.BUILTIN`), the default first.

    Returns:
        The names, comma-separated.
    """
    from styletrace.scene.builtin import BUILTIN, DEFAULT
    return ", ".join([DEFAULT, *(name for name in BUILTIN if name != DEFAULT)])


def build_parser() -> argparse.ArgumentParser:
    p = Parser(
        prog="styletrace", description="Stylized global illumination as a function of expectation."
    )
    sub = p.add_subparsers(dest="command", required=True)

    r = sub.add_parser("render", help="render a scene with a style")
    r.add_argument(
        "scene",
        nargs="*",
        default=[],
        help=f"built-in scene ({builtin_scenes()}) or a Mitsuba XML file "
        "(default: cornell-box); several XML files render as numbered frames",
    )
    r.add_argument(
        "--set",
        action="append",
        default=[],
        metavar="KEY=VALUE",
        help="a style or integrator parameter",
    )
    add_setting_flags(r)
    r.add_argument(
        "--aovs",
        dest="aovs",
        action="store_const",
        const=True,
        default=None,
        help="also write the error AOVs (variance, predicted bias, children used) as channels of "
        "the EXR output (refused with a PNG output); docs/adaptive.md",
    )
    r.add_argument(
        "--passes",
        default=None,
        metavar="LIST",
        help="also write data passes as channels of the EXR output (refused with a PNG output): "
        "a comma-separated list of depth, normal, vector, position, uv, mist, object_index, "
        "material_index, albedo, emission, Blender's Depth, Normal, Vector, Position, UV, Mist, "
        "Object Index, Material Index, Denoising Albedo and Emission (the vector is 0 but in the "
        "frames of --frames/--orbit); docs/passes.md",
    )
    r.add_argument(
        "--mist",
        default=None,
        metavar="START,DEPTH,FALLOFF",
        help="the mist pass's settings, as Blender's World: where it starts, over what distance "
        "it rises to 1, and its falloff quadratic, linear or inverse_quadratic (default "
        "5,25,quadratic, a new World's); docs/passes.md",
    )
    r.add_argument(
        "--samples",
        type=int,
        default=None,
        metavar="N",
        help="paths per pixel, the render's cost whatever the style (as Cycles' Samples), split "
        "into camera samples x children (default: the scene sampler's sample_count; 16 for the "
        "built-in scenes; docs/look.md)",
    )
    r.add_argument(
        "--spp",
        type=int,
        default=None,
        help="camera samples per pixel, each with --inner children (default: auto, from "
        "--samples)",
    )
    r.add_argument("--width", type=int, default=None,
                   help="image width (resizes the scene's film; default: the film's, 256 for the "
                   "built-in scenes but furnace, 64)")
    r.add_argument("--height", type=int, default=None,
                   help="image height (resizes the scene's film; default: as --width)")
    r.add_argument(
        "-D",
        "--define",
        action="append",
        default=[],
        metavar="NAME=VALUE",
        help="value of a <default> parameter of the scene file ($NAME), as Mitsuba's -D; "
             "repeatable",
    )
    r.add_argument(
        "--sampler", choices=SAMPLERS, default=None,
        help="a built-in scene's sample pattern: owen_sobol (the default: an Owen-scrambled "
        "Sobol sequence) or independent (the paper's protocol); a scene file names its own "
        "(<sampler type=...>; docs/design/sequence_sampler.md)",
    )
    r.add_argument(
        "--seed", type=int, default=0,
        help="random seed, 0 to 2^32 - 1; the same seed gives the same image (default: 0)"
    )
    r.add_argument(
        "--pass-spp", type=int, default=None,
        help="camera samples per pixel per pass (default: by memory)"
    )
    r.add_argument(
        "-o", "--output", default="render.png",
        help="output image: .exr (linear) or .png (sRGB) (default: render.png)"
    )
    r.add_argument("-q", "--quiet", action="store_true",
                   help="no progress bar, notes, auto values or summary")
    r.add_argument(
        "--denoise",
        choices=("auto", "expectation", "image", "off"),
        default=None,
        help="OIDN with albedo/normal guides: on the expectation before the style (first_hit), or "
        "on the final image; auto (the default, or $STYLETRACE_DENOISE): expectation where it "
        "applies, with the firefly control; off: the paper's estimators exactly "
        "(docs/denoise.md, docs/look.md)",
    )
    r.add_argument("--denoise-quality", choices=("high", "balanced", "fast"), default="high",
                   help="OIDN's filter quality with --denoise (default: high)")
    r.add_argument("--denoise-footprint", choices=("pixel", "film"), default="pixel",
                   help="what --denoise image denoises: each pixel's own samples, the film's "
                   "filter applied after (pixel, the default), or the film's image as it is (film, "
                   "the denoiser before; a tent or gaussian filter's correlated noise survives "
                   "it: docs/look.md)")
    r.add_argument(
        "--coverage",
        default=None,
        metavar="K",
        help="with --denoise expectation: points per pixel where the style is applied to the "
        "denoised expectation, a square (16, 64, ...), 0 for the camera samples, or auto (default: "
        "64, fewer where the image would not fit the buffer's cap)",
    )
    r.add_argument(
        "--denoise-uncertainty",
        default=None,
        metavar="U",
        help="with --denoise expectation and coverage points: the style is averaged over the "
        "denoised expectation's residual error, taken as U times the noisy estimate's standard "
        "error (default 0: the style of the denoised expectation itself)",
    )
    r.set_defaults(func=cmd_render)
    add_ray_flags(r)

    from styletrace.frontends import lookdev_commands as lookdev
    r.add_argument("--buffer", default=None, metavar="FILE", help=lookdev.BUFFER_HELP)
    lookdev.add_parsers(sub, parse_set=_parse_set, check_output=check_output)

    g = sub.add_parser("gallery", help="reproduce the paper's result setups on the dragon scene")
    g.add_argument("-o", "--output", default="gallery", help="output folder (default: gallery)")
    g.add_argument("--quick", action="store_true", help="small and fast (under a minute)")
    g.add_argument("--size", type=int, default=None, help="image size in pixels (square)")
    g.add_argument(
        "--only",
        default=None,
        help="comma-separated setup keys to run (equal_time: the whole "
        "equal-time section, equal_time_cel: one of its comparisons)",
    )
    g.add_argument(
        "--skip",
        default=None,
        help="comma-separated setup keys to leave out (equal_time: the equal-time section)",
    )
    g.set_defaults(func=cmd_gallery)

    s = sub.add_parser("styles", help="list the styles and their parameters")
    s.set_defaults(func=cmd_styles)
    ln = sub.add_parser(
        "lines", help="list the feature line settings (--lines, --set line_width=2, ...)"
    )
    ln.set_defaults(func=cmd_lines)
    e = sub.add_parser("estimators", help="list the estimators of g(E[L]) and the forms they need")
    e.set_defaults(func=cmd_estimators)
    return p


def add_ray_flags(parser) -> None:
    """Add the flags of rendering on Ray (styletrace.pipeline.ray_run): passes and frames as tasks,
    checkpoints, resume.

    Args:
        parser: the `render` subcommand's parser.
    """
    parser.add_argument(
        "--ray",
        nargs="?",
        const="local",
        default=None,
        metavar="ADDRESS",
        help="render the passes as Ray tasks (frames: each chunk of frames one task): on a local "
        "Ray instance, or on the cluster at ADDRESS (HOST:PORT, as printed by `ray start "
        "--head`); give it after the scene",
    )
    parser.add_argument(
        "--resume",
        action="store_true",
        help="continue an interrupted --ray render of the same output from its checkpoint "
        "(frames: render the frames not yet written, here or with --ray)",
    )
    parser.add_argument(
        "--checkpoint-every",
        type=float,
        default=None,
        metavar="SECONDS",
        help="write the --ray checkpoint at most this often (default 10; 0: after every pass)",
    )
    parser.add_argument(
        "--frames",
        type=int,
        default=None,
        metavar="N",
        help="render N frames of a turntable around the camera's target (numbered images; with "
        "--ray each chunk of frames is one Ray task)",
    )
    parser.add_argument("--orbit", type=float, default=None, metavar="DEGREES",
                        help="the turntable's total rotation about the up axis (default 360)")
    parser.add_argument(
        "--temporal-reuse",
        choices=("on", "off"),
        default="on",
        help="frames that are denoised: each its own seed, blended with the frames before it in "
        "its chunk (docs/temporal.md); off: every frame the same seed, denoised alone "
        "(default on)",
    )
    parser.add_argument(
        "--chunk",
        type=int,
        default=None,
        metavar="N",
        help="frames per chunk (default 8): temporal reuse starts afresh at each chunk's first "
        "frame; with --ray each chunk is one task",
    )


def add_setting_flags(parser) -> None:
    """Add one flag per integrator property that has one; help and defaults come from the
    settings table.

    Args:
        parser: the `render` subcommand's parser.
    """
    from styletrace.config import settings
    for p in settings.PROPERTIES:
        if not p.flag:
            continue
        default = (
            f"the scene's stylized integrator's, else {settings.COMMAND_LINE_STYLE}"
            if p.name == "style"
            else p.show_default()
        )
        # a switch (`--lines`): no value, so it never takes the scene's name; off with
        # --set NAME=false
        if p.bare:
            parser.add_argument(
                p.flag,
                dest=p.name,
                default=None,
                action="store_const",
                const="true",
                help=f"{p.doc} (default: off)",
            )
            continue
        parser.add_argument(
            p.flag,
            dest=p.name,
            default=None,
            metavar=p.metavar,
            type=int if p.kind == "int" else str,
            help=f"{p.doc} (default: {default})",
        )


#: setting flags `render` adds itself (the others come from `settings.PROPERTIES`' `flag`)
OWN_SETTING_FLAGS = {"aovs": "--aovs"}


def typed_flags(args) -> dict[str, str]:
    """The integrator properties this command line set with their own flags, and those flags.

    A property also given with `--set NAME=VALUE` is left out: that value wins
    (`command_job.given_flags`), and the user typed its name.

    Args:
        args: the parsed arguments (of any subcommand; one without setting flags gives {}).

    Returns:
        {property name: flag}, e.g. {"inner_samples": "--inner"}.
    """
    from styletrace.config import settings
    try:
        by_set = _parse_set(getattr(args, "set", None) or [])
    except UsageError:
        by_set = {}
    flags = {p.name: p.flag for p in settings.PROPERTIES if p.flag} | OWN_SETTING_FLAGS
    return {name: flag for name, flag in flags.items()
            if getattr(args, name, None) is not None and name not in by_set}


def in_flag_terms(message: str, flags: Mapping[str, str]) -> str:
    """An error of the settings (which names properties, as Python callers write them) in the
    words the user typed on the command line: `for 'inner_samples'` becomes `for --inner`, and
    `aovs=True` or `reuse=pixels` becomes `--aovs` or `--reuse pixels`, for the given flags only.

    Args:
        message: the error's one line. flags: {property: flag} (`typed_flags`).

    Returns:
        The message, translated.
    """
    for name, flag in flags.items():
        switch = name in OWN_SETTING_FLAGS or name == "lines"  # flags without a value
        if switch:  # the user typed no value: the flag itself is what is refused
            message = message.replace(f"bad value True for '{name}'", flag)
        message = message.replace(f"for '{name}'", f"for {flag}")
        message = re.sub(rf"(?<![\w.-]){re.escape(name)}=(?:True|true)\b" if switch
                         else rf"(?<![\w.-]){re.escape(name)}=(?=\w)",
                         flag if switch else f"{flag} ", message)
    return message


def main(argv: Sequence[str] | None = None) -> int:
    """The `styletrace` command.

    Args:
        argv: the arguments (None: sys.argv[1:]).

    Returns:
        The exit status: the command's; 2 after a one-line error (a StyletraceError, bad usage),
        which names a setting by the flag the user typed (`in_flag_terms`); 130 after Ctrl-C.
    """
    args = None
    try:
        # the flags' help comes from the settings table, which needs the backend: errors there are
        # one line too
        args = build_parser().parse_args(argv)
        return args.func(args)
    except KeyboardInterrupt:
        say("styletrace: interrupted")
        return 130
    except StyletraceError as exc:
        message = str(exc) if args is None else in_flag_terms(str(exc), typed_flags(args))
        say(f"styletrace: error: {message}")
        return 2


if __name__ == "__main__":
    sys.exit(main())
