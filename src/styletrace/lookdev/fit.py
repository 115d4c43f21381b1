"""Inverse stylization: θ that make a buffer's restyled image match a target image.

    result = styletrace.fit(buf, style="cel", target=img)   # .params (validated), .image

Gradient descent (Adam) through the restyle kernel with Dr.Jit's AD on the mean squared error.
Fitted: float, floats and colour parameters and a gradient's stop colours, clamped to their ranges
after each step; `fixed=` holds others. Step styles (cel, hatching) are smoothed with a temperature
τ falling from `tau` to `tau_end`; halftone is refused with one line. The `direct` estimator is
used. Rationale and the surrogates: docs/design/fitting_surrogates.md.
"""
from __future__ import annotations

import time
from dataclasses import dataclass, field
from typing import Any, Callable

import numpy as np

from styletrace.config import settings as S
from styletrace.errors import BackendError, UsageError
from styletrace.gate import dr, mi
from styletrace.lookdev.restyle import (
    accumulate,
    as_buffer,
    changed_owner,
    prepare_slots,
    sample_values,
    slots_for,
)
from styletrace.styles import create
from styletrace.styles.base import Style, brightness
from styletrace.styles.gradient import Gradient

FITTABLE = ("float", "floats", "color", "gradient")
#: parameters that stay fixed although of a fittable kind (hatching's plane normals are built in
#: Python; the tone styles' exposure is the scene's normalisation, resolved from the pilot, and for
#: contrast and reinhard it is redundant with the curve's own parameters: c (s I - p) + p and
#: s I / (w + s I) = I / (w / s + I))
NOT_FITTED = {
    "hatching": ("angle", "spacing", "thickness"),
    "contrast": ("exposure",),
    "reinhard": ("exposure",),
    "gamma": ("exposure",),
    "tie_dye": ("exposure",),
}
#: styles whose steps have no smoothed surrogate
NOT_SMOOTHED = ("halftone",)
#: parameters whose values the style requires strictly increasing (its `validate` refuses others):
#: kept sorted while fitting, and strictly increasing as printed at the end
INCREASING = {"cel": "thresholds", "color_map": "range"}


@dataclass
class FitResult:
    params: dict[str, Any]               # the fitted values, as the style's parameters take them
    loss: float                          # mean squared error of the restyled image with `params`
    # iterations run (fewer than asked where the loss reached `tol`)
    iterations: int
    seconds: float
    # loss (true style) after each checked iteration
    history: list[float] = field(default_factory=list)
    image: np.ndarray | None = None


# ---- θ as Dr.Jit arrays --------------------------------------------------------------------------

def _flatten(kind: str, value: Any) -> list[float]:
    if kind == "float":
        return [float(value)]
    if kind == "gradient":
        return [float(c) for _, col in value.stops for c in col]
    return [float(v) for v in value]


def _unflatten(kind: str, flat: mi.Float, like: Any) -> Any:
    """Parameter value from a flat Dr.Jit array (entries are width-1 arrays, so gradients flow)."""
    parts = [dr.gather(mi.Float, flat, i) for i in range(dr.width(flat))]
    if kind == "float":
        return parts[0]
    if kind == "gradient":
        stops = [(pos, tuple(parts[3 * i:3 * i + 3])) for i, (pos, _) in enumerate(like.stops)]
        return Gradient(stops, like.spec)
    return tuple(parts)


def _plain_value(kind: str, flat: np.ndarray, like: Any) -> Any:
    """The fitted value as the style's parameter parser takes it."""
    if kind == "float":
        return float(flat[0])
    if kind == "gradient":
        return [(pos, tuple(float(c) for c in flat[3 * i:3 * i + 3]))
                for i, (pos, _) in enumerate(like.stops)]
    return tuple(float(v) for v in flat)


def as_printed(p, value: Any, increasing: bool = False) -> Any:
    """A fitted value as `Param.show` prints it (6 significant digits), so that the command line
    `styletrace fit` prints gives the fit's own image.

    Args:
        p: the style's parameter. value: its validated value.
        increasing: the values must increase strictly (`INCREASING`): a value that prints equal to
            (or below) the one before it is raised to the next value that prints above it.

    Returns:
        The value `p.parse(p.show(value))`, made strictly increasing where asked.
    """
    if not increasing:
        return p.parse(p.show(value))
    out: list[float] = []
    for x in value:
        x = float(f"{x:g}")
        if out and x <= out[-1]:
            prev = out[-1]
            # one unit in the 6th significant digit of the previous value (1e-6 above 0)
            unit = 10.0 ** (np.floor(np.log10(abs(prev))) - 5) if prev else 1e-6
            x = float(f"{prev + unit:g}")
        out.append(x)
    return p.parse(",".join(f"{x:g}" for x in out))


def _clamp(p, x: mi.Float) -> mi.Float:
    if p.low is not None:
        x = dr.maximum(x, p.low + (1e-6 if p.low_open else 0.0))
    if p.high is not None:
        x = dr.minimum(x, p.high)
    return x


# ---- smoothed surrogates -------------------------------------------------------------------------

def _sigmoid(x):
    return dr.rcp(1.0 + dr.exp(-x))


class Smoothed:
    """A style whose `apply` is a smooth surrogate (`SURROGATES`); everything else delegates.

    Args:
        style: the prepared style, one of SURROGATES' (cel, hatching).
        tau: the temperature, mi.Float (the smaller, the nearer the true steps).
    """

    def __init__(self, style: Style, tau: mi.Float):
        self.style, self.tau = style, tau

    def __getattr__(self, key):
        return getattr(self.style, key)

    def apply(self, I, v):
        """The surrogate of the style's g at temperature `tau`.

        Args:
            I: mi.Color3f, the radiance estimate per lane; v: the lanes' Vertex.

        Returns:
            mi.Color3f, differentiable in the style's values and in I.
        """
        return SURROGATES[self.style.name](self.style, I, v, self.tau)


def _smooth_cel(style, I, v, tau):
    u = brightness(I)
    m = style.band_values()
    target = mi.Float(m[0])
    for j, t in enumerate(style.steps()):
        target = target + (m[j + 1] - m[j]) * _sigmoid((u - t) / tau)
    return dr.select(u > 0, I * (target / dr.maximum(u, 1e-30)), mi.Color3f(target))


def _smooth_hatching(style, I, v, tau):
    sets = len(style.normals)
    toned = style.toned(brightness(I))
    m = toned * (sets + 1) if style.uses_tones else toned * sets + 0.5
    clear = mi.Float(1.0)
    for j, nj in enumerate(style.normals):
        s = dr.dot(mi.Vector3f(v.p), mi.Vector3f(*nj)) / style.spacing + 0.5
        dist = dr.abs(s - dr.floor(s) - 0.5) * style.spacing
        line = _sigmoid((0.5 * style.thickness - dist) / (tau * style.spacing))
        active = _sigmoid((m - j - 1.0) / tau)
        clear = clear * (1.0 - line * active)
    return dr.lerp(mi.Color3f(*style.line_color), mi.Color3f(*style.background), clear)


SURROGATES: dict[str, Callable] = {"cel": _smooth_cel, "hatching": _smooth_hatching}


# ---- the loop ------------------------------------------------------------------------------------

def read_target(target: Any, width: int, height: int) -> np.ndarray:
    """The target image of a fit, as linear RGB.

    Args:
        target: an H x W x 3 array (linear), or an image file's path (EXR linear, PNG sRGB).
        width, height: the buffer's image size, which the target must have.

    Returns:
        float32 H x W x 3 linear RGB.

    Raises:
        UsageError: an unreadable file, or a target of another shape.
    """
    if isinstance(target, np.ndarray):
        img = np.asarray(target, dtype=np.float32)
    else:
        try:
            bmp = mi.Bitmap(str(target)).convert(
                pixel_format=mi.Bitmap.PixelFormat.RGB,
                component_format=mi.Struct.Type.Float32,
                srgb_gamma=False,
            )
        except Exception as exc:
            raise UsageError(
                f"cannot read target image {str(target)!r}: {str(exc).strip().splitlines()[-1]}"
            ) from None
        img = np.array(bmp, dtype=np.float32)
    if img.shape != (height, width, 3):
        raise UsageError(f"bad target image of shape {img.shape}: expected {height}x{width}x3 like "
                         "the buffer")
    return img


def fit(
    buffer: Any,
    style: str | None = None,
    target: Any = None,
    iterations: int = 300,
    lr: float = 0.1,
    tau: float = 0.1,
    tau_end: float = 1e-4,
    tol: float = 1e-9,
    fixed: tuple[str, ...] = (),
    check_every: int = 10,
    callback: Callable[[int, float], None] | None = None,
    **initial: Any,
) -> FitResult:
    """Fit a style's θ so that the restyled buffer matches a target (module doc: how).

    Takes more than 7 parameters: it is the public `styletrace.fit` (and `styletrace fit`'s), and
    each keyword is a setting its user chooses on its own (docs/lookdev.md).

    Args:
        buffer: a "mean" Buffer or its .npz path. style: the style to fit (None: the recorded).
        target: H x W x 3 linear array, or an image file (`read_target`).
        iterations, lr: Adam's steps; its learning rate, falling geometrically to lr / 100.
        tau, tau_end: the step surrogates' temperature, falling geometrically from one to the other.
        tol, check_every: stop once the true style's loss is <= tol, checked every check_every.
        fixed: parameters to keep. callback: called with (iterations done, loss) at each check.
        initial: starting values (else the recorded values, or a new style's defaults).

    Returns:
        FitResult: the fitted values (validated by the style, as `Param.show` prints them, so a
        command line of them gives `image`; `INCREASING` ones strictly increasing as printed),
        loss, iterations, image, ...

    Raises:
        BackendError: a variant without AD. UsageError: a bad target or iterations, a sequence
            buffer or one with nothing styled, halftone, an unknown fixed name, nothing to fit.
    """
    if not mi.variant().endswith("_ad_rgb") and "_ad_" not in mi.variant():
        raise BackendError("fitting needs an AD variant (llvm_ad_rgb or cuda_ad_rgb), not "
                           f"{mi.variant()}")
    if target is None:
        raise UsageError("fit needs a target image")
    if iterations < 1:
        raise UsageError(f"bad value {iterations!r} for iterations: expected an integer >= 1")
    buf = as_buffer(buffer)
    if buf.stores != "mean":
        raise UsageError(
            "fit needs a buffer of the children's mean (recorded with the direct or affine "
            "estimator); this one stores the sequences of an unbiased estimator, which Dr.Jit "
            "cannot differentiate through"
        )
    # every slot prepared on the recorded camera, 'auto' values pinned from the buffer's pilot (as a
    # render would)
    slots = prepare_slots(buf, slots_for(buf, style, "direct", None, **initial))
    owned = [i for i, r in enumerate(buf.header["slots"]) if r["owner"] == changed_owner(buf)]
    if not owned:
        raise UsageError("this buffer has no styled object to fit (first_object_hit without styled "
                         "objects)")
    base = slots[owned[0]].style
    if base.name in NOT_SMOOTHED:
        raise UsageError(
            f"style '{base.name}' cannot be fitted: its steps have no smoothed surrogate; fit one "
            "of the other styles"
        )
    for k in fixed:
        if k not in base.values:
            raise UsageError(f"bad fixed parameter {k!r}: style '{base.name}' has "
                             f"{', '.join(base.values) or 'none'}")
    free = [p for p in base.params if p.kind in FITTABLE and p.name not in fixed
            and p.name not in NOT_FITTED.get(base.name, ()) and base.values[p.name] is not None]
    if not free:
        raise UsageError(f"style '{base.name}' has no parameter to fit (fittable kinds: "
                         f"{', '.join(FITTABLE)})")
    goal = mi.Float(read_target(target, buf.width, buf.height).ravel())

    opt = dr.opt.Adam(lr=lr)
    for p in free:
        opt[p.name] = mi.Float(_flatten(p.kind, base.values[p.name]))
    tau_now = mi.Float(tau)

    def restyled(smooth: bool) -> mi.Float:
        style = create(base.name, **{k: v for k, v in base.values.items()})
        # the prepared camera etc.
        style.__dict__.update({k: v for k, v in base.__dict__.items() if k != "values"})
        for p in free:
            style.values[p.name] = _unflatten(p.kind, opt[p.name], base.values[p.name])
        used = Smoothed(style, tau_now) if smooth and base.name in SURROGATES else style
        here = [S.StyleSlot(used, s.inner, s.estimator) if i in owned else s
                for i, s in enumerate(slots)]
        return accumulate(buf, sample_values(buf, here))

    def loss_of(img):
        return dr.mean(dr.square(img - goal))

    start = time.perf_counter()
    history: list[float] = []
    done = 0
    for it in range(iterations):
        frac = it / max(iterations - 1, 1)
        opt.set_learning_rate(lr * 0.01 ** frac)
        tau_now = dr.opaque(mi.Float, tau * (tau_end / tau) ** frac)
        loss = loss_of(restyled(smooth=True))
        dr.backward(loss)
        opt.step()
        for p in free:
            x = _clamp(p, opt[p.name])
            if INCREASING.get(base.name) == p.name:
                x = mi.Float(np.sort(np.asarray(x)))
            opt[p.name] = x
        done = it + 1
        if done % check_every == 0 or done == iterations:
            with dr.suspend_grad():
                exact = float(loss_of(restyled(smooth=False))[0])
            history.append(exact)
            if callback is not None:
                callback(done, exact)
            if exact <= tol:
                break
    seconds = time.perf_counter() - start
    params = {p.name: _plain_value(p.kind, np.asarray(opt[p.name], dtype=np.float64),
                                   base.values[p.name]) for p in free}
    for p in free:  # sorted in float32 (ties possible), and printed with 6 digits
        if INCREASING.get(base.name) == p.name:
            params[p.name] = as_printed(p, params[p.name], increasing=True)
    fitted = create(base.name,
                    **{**{k: v for k, v in base.values.items() if k not in params}, **params})
    values = {p.name: as_printed(p, fitted.values[p.name]) for p in free}
    from styletrace.lookdev.restyle import restyle
    image = restyle(buf, style=base.name, **{**_given(base), **values})
    loss = float(np.mean(np.square(image.astype(np.float64)
                                   - np.asarray(goal, dtype=np.float64).reshape(image.shape))))
    return FitResult(values, loss, done, seconds, history, image)


def _given(style: Style) -> dict[str, Any]:
    return {k: v for k, v in style.values.items() if v is not None}


__all__ = ["fit", "FitResult", "SURROGATES", "Smoothed", "read_target", "as_printed",
           "INCREASING"]
