"""What a render asks of denoising, and the method it gets: the first thing `resolve` decides.

    d = Denoising(method="auto", quality="high")           # every front end's options, one value
    method, note = choose_method(scene, integrator, request, d, local=True)

`auto` (every front end's default, `default_method`) is `expectation` where the expectation
denoiser applies to a style whose camera samples average more than one child, `image` where the
image denoiser takes the render, else `off` with a one-line note. The method is chosen before the
samples are split (`pipeline.budget.averages_children` reads the request, not a split), so that
`resolve` splits them once, for the method. The denoisers themselves, and the checks of quality,
coverage, uncertainty and footprint, are `denoise/`'s. Design: docs/design/denoise_defaults.md.
"""
from __future__ import annotations

import os
from dataclasses import dataclass, field
from typing import Any

from styletrace.errors import UsageError

#: the denoising methods; `auto` chooses among the other three (`choose_method`)
METHODS = ("auto", "expectation", "image", "off")
#: the environment variable that sets the default method of every front end (unset: auto)
ENV = "STYLETRACE_DENOISE"
#: the firefly control's k where a render denoises
FIREFLY_K = 4.0


def check_method(method) -> str:
    """`method` if it is one of METHODS.

    Args:
        method: the denoising method asked for.

    Returns:
        `method`.

    Raises:
        UsageError: any other value (one line).
    """
    if method not in METHODS:
        raise UsageError(f"bad value {method!r} for denoise: expected one of {', '.join(METHODS)}")
    return method


def default_method() -> str:
    """The default of `--denoise` / `denoise=` in every front end: $STYLETRACE_DENOISE, else auto.

    Raises:
        UsageError: $STYLETRACE_DENOISE names no method (one line).
    """
    value = os.environ.get(ENV, "").strip().lower() or "auto"
    if value not in METHODS:
        raise UsageError(f"bad value {value!r} for ${ENV}: expected one of {', '.join(METHODS)}")
    return value


@dataclass(frozen=True)
class Denoising:
    """The denoising options of a render, one value from each front end down to the finisher.

    Args:
        method: auto, expectation, image or off (None: `default_method()`, read when made).
        quality: OIDN's "high", "balanced" or "fast".
        coverage: points per pixel where g meets the denoised expectation ("auto", 0 or a
            square; `denoise.coverage.check_k`).
        uncertainty: `denoise.expectation.spread`'s factor (None: its default).
        footprint: what the image denoiser denoises, "pixel" or "film" (`denoise.image`).
        history: the frames' temporal history (`denoise.temporal.History`): the estimate OIDN
            meets is blended with it and, once the result is final, kept in it; None: none (not
            compared: two options that differ only in it are equal).

    Raises:
        UsageError: an unknown method (one line); the other values are checked by the finisher
            that uses them.
    """
    method: str | None = None
    quality: str = "high"
    coverage: int | str = "auto"
    uncertainty: float | None = None
    footprint: str = "pixel"
    history: Any = field(default=None, compare=False)

    def __post_init__(self):
        method = default_method() if self.method is None else self.method
        object.__setattr__(self, "method", check_method(method))


#: no denoising: the paper's estimators exactly
OFF = Denoising("off")


def expectation_refusal(integrator) -> str:
    """Why the expectation denoiser cannot render `integrator` ('' where it can).

    Supported: `first_hit` with the integrator's style and per-object (`styled`) styles,
    `first_object_hit` (a vertex behind a mirror, glass or a bounce takes its pixel's D:
    docs/look.md), the estimators of the children's mean (`MEAN_ESTIMATORS`), fixed counts n
    (films other than rgb: the buffer's refusal).

    Args:
        integrator: the render's `stylized` integrator.

    Returns:
        One line ('stylize=first_n_hits: ...'), or ''.
    """
    # config loads Dr.Jit: imported here, so that the command line's parser (which makes Jobs'
    # fields) does not
    from styletrace.config import settings as S
    from styletrace.config.estimator_registry import MEAN_ESTIMATORS
    s = integrator.settings
    if s.stylize == "first_n_hits" or s.stylize_depth != 1:
        return ("stylize=first_n_hits: nested levels have no per-pixel expectation to denoise (the "
                "inner levels' vertices are not the pixel's); use first_hit or --denoise image")
    if s.lines is not None:
        return "feature lines: lines replace radiance inside the estimate; use --denoise image"
    if s.reuse != "off":
        return f"reuse={s.reuse}: denoising and reuse both filter the expectation; use one"
    if s.expansion_pass:
        return ("expansion_pass: it serves the series estimators, which denoising replaces by "
                "direct application")
    if s.slot.estimator not in MEAN_ESTIMATORS:
        return (f"estimator '{s.slot.estimator}': the denoised expectation is styled by direct "
                "application; use direct or affine")
    if S.adaptive(s.inner):
        return "adaptive counts n0:n_max: give a fixed count (the denoiser does the averaging)"
    if s.style.per_sample:
        return (f"style '{s.style.name}': it applies g to every child, there is no expectation to "
                "denoise")
    return ""


def check_expectation(integrator) -> None:
    """Refuse what the expectation denoiser does not support (`expectation_refusal`).

    Raises:
        UsageError: one line, "--denoise expectation cannot render ...".
    """
    why = expectation_refusal(integrator)
    if why:
        raise UsageError(f"--denoise expectation cannot render {why}")


def oidn_installed() -> bool:
    """Whether pyoidn (the `denoise` extra) can be imported."""
    try:
        import pyoidn  # noqa: F401
    except ImportError:
        return False
    return True


def why_not(scene, integrator, local: bool = True, method: str = "expectation") -> str:
    """Why `method` cannot denoise `integrator` on `scene`.

    Args:
        scene: the loaded scene (its film; None where there is none to ask). integrator: the
            render's integrator. local: the render runs in one process. method: "expectation" or
            "image".

    Returns:
        One line saying why not (for expectation Ray, for image Ray with a film filter other
        than a box; no OIDN, a film other than rgb, and for expectation its refusals:
        `expectation_refusal`), or '' where it can.
    """
    from styletrace.kernel.integrator import StylizedIntegrator
    from styletrace.scene.loading import film_format
    if not local and method == "expectation":
        return ("the render runs on Ray; the expectation denoiser needs every camera sample in one "
                "process")
    if isinstance(integrator, StylizedIntegrator) and integrator.settings.light_groups:
        return ("light groups are not yet denoised (docs/light_groups.md); use denoise off")
    if not oidn_installed():
        return "Intel Open Image Denoise is not installed (pip install 'styletrace[denoise]')"
    if film_format(scene) != "rgb":
        return f"the film's pixel_format is '{film_format(scene)}', not rgb"
    if method == "image":
        if not local and scene is not None and not scene.sensors()[0].film().rfilter() \
                .is_box_filter():
            return ("the render runs on Ray with a film filter other than a box; the image "
                    "denoiser needs each pixel's own samples in one process")
        return ""
    if not isinstance(integrator, StylizedIntegrator):
        return f"the integrator is Mitsuba's {type(integrator).__name__}, not stylized"
    return expectation_refusal(integrator)


def choose_method(scene, integrator, request, denoising: Denoising, local: bool = True,
                  cap: int | None = None) -> tuple[str, str]:
    """The method a render gets: auto decided (the module doc), the others as asked.

    Args:
        scene, integrator: the render's (the integrator before its count is split).
        request: its `pipeline.budget.Request`, not yet split.
        denoising: the options; their method is auto, expectation, image or off.
        local: the render runs in one process.
        cap: the most camera samples the expectation buffer holds (a given spp over it leaves auto
            the image denoiser), or None.

    Returns:
        (expectation | image | off, the one-line note where auto could not denoise, else '').
    """
    from styletrace.kernel.integrator import StylizedIntegrator
    from styletrace.pipeline.budget import averages_children
    grouped = isinstance(integrator, StylizedIntegrator) and integrator.settings.light_groups
    if grouped and denoising.method not in ("auto", "off"):
        raise UsageError(f"bad value {denoising.method!r} for denoise with light_groups: light "
                         "groups are not yet denoised; use off")
    if denoising.method != "auto":
        return denoising.method, ""
    why = why_not(scene, integrator, local, "expectation")
    if not why and cap is not None and request.camera_samples is not None:
        size = scene.sensors()[0].film().crop_size()
        given = int(size[0]) * int(size[1]) * int(request.camera_samples)
        if given > cap:
            why = f"{given} camera samples, over the expectation buffer's cap of {cap}"
    if not why and averages_children(request):
        return "expectation", ""
    image_why = why_not(scene, integrator, local, "image")
    if image_why:
        return "off", f"not denoised: {image_why}"
    if why.startswith("feature lines"):  # the image denoiser would blur the lines away
        return "off", f"not denoised: {why}"
    return "image", ""


__all__ = ["Denoising", "OFF", "METHODS", "ENV", "FIREFLY_K", "check_method", "default_method",
           "expectation_refusal", "check_expectation", "why_not", "choose_method",
           "oidn_installed"]
