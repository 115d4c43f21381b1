"""The denoiser itself: Intel Open Image Denoise (`pyoidn`) on the CPU, Mitsuba's OptiX denoiser
on CUDA.

    out = denoise_oidn(color, albedo, normal, quality="high")   # H x W x 3 float32, linear HDR

The colour is treated as HDR (`hdr=True`: linear radiance, not display values) and the guides as
clean (`cleanAux=True`): they come from the same camera rays as the colour and carry no Monte
Carlo noise of the children, whose noise is the one removed here (docs/denoise.md). `pyoidn` (and
`cffi`) are the `styletrace[denoise]` extra; `require()` refuses in one line without it.
"""
from __future__ import annotations

import numpy as np

from styletrace.errors import UsageError

QUALITIES = ("high", "balanced", "fast")
EXTRA = "pip install 'styletrace[denoise]'"


def require():
    """The pyoidn module.

    Raises:
        UsageError: pyoidn is not installed (one line naming the extra).
    """
    try:
        import pyoidn
    except ImportError:
        raise UsageError(
            f"--denoise needs Intel Open Image Denoise (pyoidn), the 'denoise' extra: {EXTRA}"
        ) from None
    return pyoidn


def check_quality(quality: str) -> str:
    """`quality` if it is one of OIDN's filter qualities (QUALITIES).

    Args:
        quality: "high", "balanced" or "fast".

    Returns:
        `quality`.

    Raises:
        UsageError: any other value (one line).
    """
    if quality not in QUALITIES:
        raise UsageError(
            f"bad value {quality!r} for denoise quality: expected one of {', '.join(QUALITIES)}"
        )
    return quality


def _as_rgb(a) -> np.ndarray:
    a = np.asarray(a, dtype=np.float32)
    return np.ascontiguousarray(np.nan_to_num(a[..., :3], nan=0.0, posinf=0.0, neginf=0.0))


def denoise_oidn(color, albedo, normal, quality: str = "high", to_sensor=None) -> np.ndarray:
    """Denoise a colour image with its guides (OptiX on CUDA, where Mitsuba has it; else OIDN).

    Args:
        color: H x W x 3 linear radiance (NaN, inf as 0). albedo, normal: the guides, H x W x 3.
        quality: OIDN's "high", "balanced" or "fast" (OptiX has none).
        to_sensor: the sensor's world-to-camera transform, for OptiX's normals (None: world space).

    Returns:
        The denoised image, H x W x 3 float32.

    Raises:
        UsageError: a bad quality, or no pyoidn where OIDN is needed.
    """
    check_quality(quality)
    color, albedo, normal = _as_rgb(color), _as_rgb(albedo), _as_rgb(normal)
    import mitsuba as mi
    if mi.variant() and mi.variant().startswith("cuda") and hasattr(mi, "OptixDenoiser"):
        return _optix(color, albedo, normal, to_sensor)
    pyoidn = require()
    return np.asarray(
        pyoidn.denoise(color, albedo, normal, hdr=True, clean_aux=True, quality=quality),
        dtype=np.float32,
    )


def _optix(color, albedo, normal, to_sensor) -> np.ndarray:
    """CUDA only, UNTESTED (the development machines have no GPU): Mitsuba's OptiX AI denoiser with
    the same guides. OptiX wants normals in the sensor's frame, hence `to_sensor` (the sensor's
    world-to-camera transform; None keeps world space)."""
    import mitsuba as mi
    h, w = color.shape[:2]
    den = mi.OptixDenoiser(
        input_size=mi.ScalarVector2u(w, h), albedo=True, normals=True, temporal=False
    )
    kwargs = {"albedo": mi.TensorXf(albedo), "normals": mi.TensorXf(normal)}
    if to_sensor is not None:
        kwargs["to_sensor"] = to_sensor
    return np.asarray(den(mi.TensorXf(color), **kwargs), dtype=np.float32)


__all__ = ["denoise_oidn", "require", "check_quality", "QUALITIES", "EXTRA"]
