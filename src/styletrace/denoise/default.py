"""What a render does at defaults: denoise where it can, with the firefly control and the
buffer's cap on camera samples.

    plan = choose(resolved, method="auto", local=True)
    plan.method, plan.resolved, plan.note   # expectation | image | off, the pinned job, why not

`auto` (every front end's default, `default_method`) is `expectation` where the expectation
denoiser applies to a style of more than one child, `image` where the image denoiser takes the
render, else `off` with a one-line note (`method_for`). A render that denoises also gets, unless
the caller set them, the firefly control (`with_firefly`) and, without a given spp, the scene's
samples split again where it denoises the expectation (`pin_denoise_budget`: at most
`pipeline.budget.CHILDREN` children, within the buffer's cap).
Design: docs/design/denoise_defaults.md.
"""
from __future__ import annotations

import os
from dataclasses import dataclass, replace

from styletrace.errors import UsageError

#: the denoising methods; `auto` chooses among the other three (`method_for`)
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
class Plan:
    method: str          # expectation | image | off
    resolved: object     # pipeline.resolve.Resolved, with the values chosen here pinned
    note: str = ""       # why auto did not denoise ('' where it did or was not asked to)


def why_not(scene, integrator, local: bool = True, method: str = "expectation") -> str:
    """Why `method` cannot denoise `integrator` on `scene`.

    Args:
        scene: the loaded scene (its film). integrator: the render's integrator.
        local: the render runs in one process. method: "expectation" or "image".

    Returns:
        One line saying why not (Ray or several images, no OIDN, a film other than rgb, and for
        expectation its refusals: `expectation.check_expectation`), or '' where it can.
    """
    from styletrace.kernel.integrator import StylizedIntegrator
    from styletrace.scene.loading import film_format
    if not local:
        return ("the render runs on Ray or as several images; the denoiser needs the whole image "
                "in one process")
    try:
        import pyoidn  # noqa: F401
    except ImportError:
        return "Intel Open Image Denoise is not installed (pip install 'styletrace[denoise]')"
    if film_format(scene) != "rgb":
        return f"the film's pixel_format is '{film_format(scene)}', not rgb"
    if method == "image":
        return ""
    if not isinstance(integrator, StylizedIntegrator):
        return f"the integrator is Mitsuba's {type(integrator).__name__}, not stylized"
    from styletrace.denoise import expectation
    try:
        expectation.check_expectation(integrator)
    except UsageError as exc:
        return str(exc).replace("--denoise expectation cannot render ", "")
    return ""


def nonlinear(integrator) -> bool:
    """Whether denoising the expectation before g differs from denoising the image after it.

    Args:
        integrator: the render's integrator.

    Returns:
        True where the first stylized level applies a style that is not per-sample to a mean of
        more than one child; False for any integrator but `stylized`.
    """
    from styletrace.kernel.integrator import StylizedIntegrator
    if not isinstance(integrator, StylizedIntegrator):
        return False
    slot = integrator.settings.slot
    n = slot.n(0)
    return not slot.style.per_sample and int(n) > 1


def method_for(scene, integrator, method: str | None = None, local: bool = True, samples: int = 0
               ) -> tuple[str, str]:
    """The method a render gets: auto decided (see the module doc), the others as asked.

    Args:
        scene, integrator: the render's. method: auto, expectation, image, off (None: the default).
        local: the render runs in one process. samples: the camera samples of a given spp (width x
            height x spp), which the expectation's buffer must hold; 0 where spp is not given.

    Returns:
        (expectation | image | off, the one-line note where auto could not denoise, else '').

    Raises:
        UsageError: an unknown method.
    """
    method = check_method(method or default_method())
    if method != "auto":
        return method, ""
    from styletrace.lookdev.buffer import MAX_SAMPLES
    why = why_not(scene, integrator, local, "expectation")
    if not why and samples > MAX_SAMPLES:
        why = f"{samples} camera samples, over the expectation buffer's cap of {MAX_SAMPLES}"
    if not why and nonlinear(integrator):
        return "expectation", ""
    image_why = why_not(scene, integrator, local, "image")
    if image_why:
        return "off", f"not denoised: {image_why}"
    if why and why.startswith("feature lines"):  # the image denoiser would blur the lines away
        return "off", f"not denoised: {why}"
    return "image", ""


def choose(resolved, method: str | None = None, local: bool = True) -> Plan:
    """The plan of a resolved job: its method, and the job with the values chosen for it pinned.

    Args:
        resolved: the resolved job (`pipeline.resolve.Resolved`).
        method: auto, expectation, image or off (None: the default). local: in one process.

    Returns:
        The `Plan`: the method, the job (`pin_denoise_budget`'s where it denoises), the note.
    """
    w, h = resolved.size
    given = 0 if resolved.job.spp is None else w * h * int(resolved.spp)
    method, note = method_for(resolved.scene, resolved.integrator, method, local, given)
    if method == "off":
        return Plan("off", resolved, note)
    return Plan(method, pin_denoise_budget(resolved, method), note)


def resplit(resolved, request, cap: int | None = None):
    """`resolved` with its budget split again for `request` (`pipeline.budget.split`).

    Args:
        resolved: the resolved job. request: the budget's request, changed. cap: the most camera
            samples per pixel an auto spp may take, or None.

    Returns:
        `resolved` itself where the split is the same or it has no budget or no `stylized`
        integrator; else a copy with the new children, spp and `auto` line.
    """
    from styletrace.kernel.integrator import StylizedIntegrator
    from styletrace.pipeline.budget import split
    from styletrace.pipeline.resolve import with_inner
    budget = resolved.budget
    if budget is None or not isinstance(resolved.integrator, StylizedIntegrator):
        return resolved
    again = split(request, cap)
    if again == budget:
        return resolved
    auto = resolved.auto.replace(budget.note, again.note) if budget.note else resolved.auto
    return replace(resolved, integrator=with_inner(resolved.integrator, again.inner),
                   spp=again.spp, auto=auto, budget=again)


def with_firefly(scene, integrator, method: str, pilot=None):
    """The firefly control a render of `method` gets at its default: on where it denoises, unless
    `firefly` was given or error AOVs (which describe the paper's estimator) are on.

    Args:
        scene: the scene. integrator: the `stylized` integrator. method: the chosen method.
        pilot: the scene-defaults pilot to measure the control's floor with (None: a new one).

    Returns:
        (the integrator, with firefly = FIREFLY_K pinned where it applies; the note naming it).
    """
    from styletrace.scene.defaults import pin_firefly
    s = integrator.settings
    if method == "off" or s.firefly is not None or s.aovs:
        return integrator, ""
    return pin_firefly(scene, integrator, pilot, FIREFLY_K)


def pin_denoise_budget(resolved, method: str):
    """`resolved` with the firefly control on and, for the expectation denoiser, the budget split
    for it: at most `pipeline.budget.CHILDREN` children, an auto spp within its buffer's cap.

    Args:
        resolved: the resolved job. method: "expectation" or "image".

    Returns:
        A copy with the firefly control (`with_firefly`) and, with expectation, the budget split
        again as denoised, within MAX_SAMPLES // (w x h) camera samples per pixel
        (`pipeline.budget.split`: an auto spp lowered to the cap, an auto n raised to
        ceil(samples / spp)); its `auto` line names the values. Other integrators: as they are.
    """
    from styletrace.kernel.integrator import StylizedIntegrator
    if not isinstance(resolved.integrator, StylizedIntegrator):
        return resolved
    if method == "expectation" and resolved.budget is not None:  # within what the buffer holds
        from styletrace.lookdev.buffer import MAX_SAMPLES
        w, h = resolved.size
        # g meets the denoised expectation: at most CHILDREN children (`pipeline.budget`)
        request = replace(resolved.budget.request, denoised=True)
        resolved = resplit(resolved, request, MAX_SAMPLES // (w * h))
    integrator, note = with_firefly(resolved.scene, resolved.integrator, method, resolved.pilot)
    auto = "; ".join(a for a in (resolved.auto, note) if a)
    return replace(resolved, integrator=integrator, auto=auto)


__all__ = [
    "METHODS",
    "ENV",
    "check_method",
    "default_method",
    "Plan",
    "choose",
    "method_for",
    "why_not",
    "nonlinear",
    "with_firefly",
    "pin_denoise_budget",
    "resplit",
    "FIREFLY_K",
]
