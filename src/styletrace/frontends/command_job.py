"""The command line's render description: a pipeline `Job` from `styletrace render`'s
parsed arguments.

    job = job_of(args, params={"thresholds": "0.3"}, defines={"depth": "3"})

The integrator values given are the setting flags that were used (each property's flag,
`settings.PROPERTIES`) and the `--set` values; a scene without a `stylized` integrator starts from
`settings.COMMAND_LINE_STYLE`. `render`, `render --buffer`, `--ray` and the frames/orbit runner all
build their job here.
"""
from __future__ import annotations

from typing import Any, Mapping

from styletrace.pipeline.denoising import Denoising
from styletrace.pipeline.job import Job
from styletrace.pipeline.terms import COMMAND_LINE


def given_flags(args, params: Mapping[str, Any]) -> dict[str, Any]:
    """The integrator values the user gave: the setting flags that were used, then `--set` values.

    Args:
        args: the parsed arguments of `styletrace render`.
        params: the `--set` values, {name: text}.

    Returns:
        {property name: value}.
    """
    from styletrace.config import settings
    given = {p.name: getattr(args, p.name, None) for p in settings.PROPERTIES
             # (properties without a flag come by --set)
             if getattr(args, p.name, None) is not None}
    given.update(params)
    return given


def denoising_of(args) -> Denoising:
    """The denoising options of `styletrace render`'s flags (`--denoise`, `--denoise-quality`,
    `--coverage`, `--denoise-uncertainty`, `--denoise-footprint`).

    Args:
        args: the parsed arguments; a flag it lacks takes the option's default.

    Returns:
        The `pipeline.denoising.Denoising` (method None: $STYLETRACE_DENOISE, else auto).

    Raises:
        UsageError: $STYLETRACE_DENOISE names no method (one line).
    """
    coverage = getattr(args, "coverage", None)
    return Denoising(getattr(args, "denoise", None), getattr(args, "denoise_quality", "high"),
                     "auto" if coverage is None else coverage,
                     getattr(args, "denoise_uncertainty", None),
                     getattr(args, "denoise_footprint", "pixel"))


def job_of(
    args, params: Mapping[str, Any], defines: Mapping[str, Any] | None = None, scene: Any = None
) -> Job:
    """The job of `styletrace render`, in the command line's terms (`pipeline.terms`).

    Args:
        args: its parsed arguments (size, samples, spp, seed, pass split, setting flags, denoising,
            data passes).
        params: the `--set` values. defines: the `-D` values, or None.
        scene: one of several scene arguments (None: `args.scene`, its first where a list).

    Returns:
        The `pipeline.job.Job`; a scene without a `stylized` integrator starts from
        `settings.COMMAND_LINE_STYLE`.
    """
    from styletrace.config import settings
    if scene is None:  # `render` takes several scene arguments (frames); a single render the first
        scene = args.scene[0] if isinstance(args.scene, list) and args.scene else args.scene
    return Job(
        scene=scene or None,
        defines=dict(defines or {}),
        width=args.width,
        height=args.height,
        sampler=getattr(args, "sampler", None),
        given=given_flags(args, params),
        default_style=settings.COMMAND_LINE_STYLE,
        spp=args.spp,
        seed=args.seed,
        pass_spp=args.pass_spp,
        samples=getattr(args, "samples", None),
        denoising=denoising_of(args),
        terms=COMMAND_LINE,
        data_passes=getattr(args, "passes", None) or (),
        mist=getattr(args, "mist", None),
    )


__all__ = ["job_of", "given_flags", "denoising_of"]
