"""Denoising at a budget (issue 21): `styletrace.render(..., denoise="expectation" | "image")`.

- `expectation` (`denoise.expectation`): denoise the per-pixel estimate of E[L] at the first stylized vertex,
  then apply g. Step styles (cel, hatching) stay free of band flips; works through the expectation buffer,
  which keeps the denoised expectation for millisecond restyles.
- `image` (`denoise.image`): render as usual and denoise the final image; the baseline.

Both use OIDN (`pyoidn`, the `styletrace[denoise]` extra) with albedo and normal guides (through mirrors and glass)
(`denoise.guides`), or Mitsuba's OptiX denoiser on CUDA (`denoise.oidn`, untested). Method, bias and the
supported combinations: docs/denoise.md.

`render` parameters: as `styletrace.render` (scene, style, spp=16, inner, estimator, seed=0, width, height,
integrator, callback, **params), plus `denoise` (auto, expectation, image or off; the default of every front
end is auto, or $STYLETRACE_DENOISE: `default_method`), `denoise_quality` ("high"), and for
`expectation` `coverage` ("auto": 64 points per pixel where the style meets D, `denoise.coverage`) and
`denoise_uncertainty` (0.3: the style averaged over D's residual error, `expectation.spread`; 0 for g of D).
Returns the image, or (image, aovs) with `aovs=True`.
"""
from __future__ import annotations

from typing import Any

from ..errors import UsageError
from .default import ENV, METHODS, check_method, default_method


class NotDenoised(UserWarning):
    """Issued by `render` where the default (auto) could not denoise; the message says why, in one line."""


def render(scene: Any = None, style: str | None = None, spp: int | None = None, inner: Any = None,
           estimator: str | None = None, seed: int = 0, width: int | None = None, height: int | None = None,
           integrator: Any = None, callback: Any = None, denoise: str = "auto",
           denoise_quality: str = "high", pass_spp: int | None = None, defines: dict[str, Any] | None = None,
           coverage: int | str = "auto", denoise_uncertainty: float | None = None, **params: Any):
    """`styletrace.render(..., denoise=...)`: the render pipeline's job (`pipeline.resolve`: the scene's own
    settings merged, auto values pinned), planned (`denoise.default.choose`: auto picks expectation where it
    applies, else renders as the pipeline does and warns `NotDenoised`), rendered and denoised here
    (docs/denoise.md)."""
    check_method(denoise)
    from . import coverage as points
    from . import oidn
    points.check_k(coverage)
    from .expectation import UNCERTAINTY, check_uncertainty
    uncertainty = check_uncertainty(UNCERTAINTY if denoise_uncertainty is None else denoise_uncertainty)
    oidn.check_quality(denoise_quality)
    from ..pipeline.job import python_job
    from ..pipeline.resolve import resolve
    from ..pipeline.scene import film_format
    from .default import choose
    r = resolve(python_job(scene, style, spp, inner, estimator, seed, width, height, integrator, defines, pass_spp,
                           **params))
    plan = choose(r, denoise)
    if plan.method == "off":
        import warnings

        from ..pipeline.execute import run
        if plan.note:
            warnings.warn(plan.note, NotDenoised, stacklevel=3)
        return run(plan.resolved, None, callback)
    oidn.require()
    r = plan.resolved
    sc, integrator, spp = r.scene, r.integrator, r.spp
    want_aovs = bool(integrator.settings.aovs)
    if want_aovs and spp < 2:
        raise UsageError(f"bad value {spp} for 'spp' with aovs=True: the variance needs at least 2 samples per pixel")
    if film_format(sc) != "rgb":
        raise UsageError(f"--denoise needs an rgb film, not '{film_format(sc)}'")
    if plan.method == "expectation":
        from ..lookdev.record import scene_label
        from . import expectation
        image, buf = expectation.render(sc, integrator, spp, seed, denoise_quality, callback,
                                        label=scene_label(scene), coverage=coverage, uncertainty=uncertainty,
                                        lanes_per_pass=r.lanes, pass_spp=pass_spp)
        return (image, expectation.aovs(buf, image)) if want_aovs else image
    from . import image as post
    out, _, errs = post.render(sc, integrator, spp, seed, denoise_quality, callback,
                               lanes_per_pass=r.lanes, pass_spp=pass_spp)
    return (out, errs) if want_aovs else out


__all__ = ["render", "METHODS", "ENV", "NotDenoised", "check_method", "default_method"]
