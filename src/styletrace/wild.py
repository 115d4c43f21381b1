"""Wild estimates: pixel values an unbiased estimator put outside the range its style can take.

For the integrator's own style slot, when its estimator is not `direct` and its form declares
the values g takes on radiance >= 0 (`SeriesForm.values`): the fraction of finite channel values
outside that range by more than TOLERANCE times the image's median |value|, reported when it is
at least WILD_FRACTION. Styles on per-object `styled` BSDFs are not checked. Rationale:
docs/design/wild_estimates.md.
"""
from __future__ import annotations

import numpy as np

__all__ = ["WILD_FRACTION", "TOLERANCE", "measure", "warning"]

#: report when at least this fraction of channel values is wild (1 in 1000)
WILD_FRACTION = 1e-3
#: a value is wild when outside g's range by more than this times the image's median |value|
TOLERANCE = 0.1


def measure(image, lo, hi):
    """Measure how many channel values lie outside [lo, hi] by more than the tolerance.

    Args:
        image: array-like of channel values (non-finite ones are ignored).
        lo: the low end of g's range.
        hi: the high end, or None for no upper end.

    Returns:
        (wild fraction, observed min, observed max, median |value|) of the finite values; a value
        is wild outside [lo, hi] by more than TOLERANCE times the median. All 0 without finite ones.
    """
    x = np.asarray(image, dtype=np.float64)
    x = x[np.isfinite(x)]
    if x.size == 0:
        return 0.0, 0.0, 0.0, 0.0
    med = float(np.median(np.abs(x)))
    tol = TOLERANCE * med
    wild = x < lo - tol
    if hi is not None:
        wild |= x > hi + tol
    return float(np.count_nonzero(wild)) / x.size, float(x.min()), float(x.max()), med


def warning(image, settings) -> str | None:
    """The warning for a render whose estimates are wild (see the module doc).

    Args:
        image: the rendered image (linear channel values).
        settings: the integrator's parsed settings: its slot (style, estimator) and
            `expansion_pass`, which choose the advice.

    Returns:
        A one-line warning when at least WILD_FRACTION of the values are wild, else None (also for
        the `direct` estimator and for a style whose form declares no range).
    """
    slot = settings.slot
    if slot.estimator == "direct":
        return None
    values = getattr(slot.style.form(), "values", None)
    if values is None:
        return None
    lo, hi = values
    fraction, vmin, vmax, med = measure(image, lo, hi)
    if fraction < WILD_FRACTION:
        return None
    span = f"[{lo:g}, inf)" if hi is None else f"[{lo:g}, {hi:g}]"
    # the series estimator without its expansion pass: the pass is the first thing to try
    # (docs/estimators.md)
    advice = ("use --expansion-pass 64 or --estimator direct" if slot.estimator == "series"
              and not getattr(settings, "expansion_pass", 0) else "use --estimator direct")
    return (
        f"the '{slot.estimator}' estimator's {slot.style.name} estimates are wild: "
        f"{100 * fraction:.2g}% of pixel values lie outside {slot.style.name}'s range {span} "
        f"(observed {vmin:.3g} to {vmax:.3g}, median |value| {med:.3g}); its variance is unbounded "
        f"on radiance with fireflies (small bright lights, glossy highlights): {advice}, or see "
        "docs/estimators.md (Gamma and the series estimators)"
    )
