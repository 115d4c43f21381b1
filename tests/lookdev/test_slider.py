"""Restyles at slider speed (`Style.opaque`, `slider.quick_restyle`).

- Every restyle passes the style's real parameters to its kernel as inputs: after the first value
  of a parameter, a new value launches only kernels already compiled (Dr.Jit's kernel history:
  every JIT kernel a cache hit), for every style that takes such a parameter.
- The image is the one with θ as literals (the kernel the render traces), to float rounding
  (LLVM folds literal constants, so the last bit may differ), for every restylable style.
- `quick_restyle` is the restyle of the buffer's one-point-per-pixel view; its pixels encoded on
  the device (`quick_restyle_pixels`) are `images.srgb8` of it, bit for bit.
"""
from dataclasses import replace

import numpy as np
import pytest

from styletrace.gate import dr
from styletrace.lookdev.record import render_buffer
from styletrace.lookdev.restyle import (
    accumulate,
    per_pixel,
    prepare_slots,
    restyle,
    sample_values,
    slots_for,
)
from styletrace.lookdev.slider import quick_restyle, quick_restyle_pixels, srgb8_rgba
from styletrace.styles import registry

W, H = 12, 10
#: styles a buffer of means restyles (not the per-sample baseline)
STYLES = [s for s in registry.style_names() if not registry.style_class(s).per_sample]


@pytest.fixture(scope="module")
def buf():
    return render_buffer("cornell-box", style="cel", spp=2, inner=4, seed=5, width=W, height=H)


def literal(buf, **kw):
    """The restyle with θ as literals: what the kernel of a render traces."""
    slots = prepare_slots(buf, slots_for(buf, **kw))
    img = accumulate(buf, sample_values(buf, slots))
    return np.asarray(img, dtype=np.float32).reshape(buf.height, buf.width, 3)


@pytest.mark.parametrize("style", STYLES)
def test_theta_as_inputs_gives_the_literal_image(buf, style):
    got, want = restyle(buf, style=style), literal(buf, style=style)
    np.testing.assert_allclose(got, want, rtol=1e-5, atol=1e-7)


def real_parameter(style):
    """A float parameter of `style` with a default, or None."""
    return next((p for p in registry.style_class(style).params
                 if p.kind == "float" and p.default is not None), None)


def kernels(fn):
    """The hashes of the JIT kernels `fn` launches, and its result."""
    dr.set_flag(dr.JitFlag.KernelHistory, True)
    try:
        dr.kernel_history()  # cleared
        out = fn()
        return {k["hash"] for k in dr.kernel_history() if k["type"] == dr.KernelType.JIT}, out
    finally:
        dr.set_flag(dr.JitFlag.KernelHistory, False)


@pytest.mark.parametrize("style", [s for s in STYLES if real_parameter(s) is not None]
                         + ["cel"])
def test_a_new_value_launches_the_same_kernels(buf, style):
    """The same kernel hashes for two values (literals would differ: a value is part of a traced
    kernel's hash, and the disk cache would hide a compile from `cache_hit`)."""
    p = real_parameter(style)
    name, values = ((p.name, [p.default * 1.1 + 0.01, p.default * 1.2 + 0.02]) if p else
                    ("levels", ["0.05,0.2,0.6", "0.07,0.25,0.7"]))
    first, _ = kernels(lambda: restyle(buf, style=style, **{name: values[0]}))
    second, image = kernels(lambda: restyle(buf, style=style, **{name: values[1]}))
    assert first and first == second
    # and the opaque values did reach the kernel: the image is the new value's
    np.testing.assert_allclose(image, literal(buf, style=style, **{name: values[1]}),
                               rtol=1e-5, atol=1e-7)


def test_opaque_leaves_the_style_as_it_was(buf):
    slot = prepare_slots(buf, slots_for(buf, style="gamma", gamma=1.8))[0]
    copy = slot.style.opaque()
    assert slot.style.values["gamma"] == 1.8 and isinstance(slot.style.values["gamma"], float)
    assert not isinstance(copy.values["gamma"], float)
    assert replace(slot, style=copy).style is copy
    assert isinstance(slot.style.opaque(names=()).values["gamma"], float)  # only those named


def test_quick_restyle_is_the_restyle_of_the_one_point_view(buf):
    np.testing.assert_array_equal(quick_restyle(buf, style="cel", levels="0.1,0.3,0.7"),
                                  restyle(per_pixel(buf), style="cel", levels="0.1,0.3,0.7"))


def test_the_pixels_encoded_on_the_device_are_srgb8_of_the_quick_restyle():
    """The page's 8-bit sRGB RGBA (`quick_restyle_pixels`) equals `images.srgb8` of the quick
    restyle, bit for bit, including values out of [0, 1] and NaN (clamped, NaN as 0)."""
    from styletrace.gate import mi
    from styletrace.images import srgb8
    buf = render_buffer("cornell-box", style="cel", spp=2, inner=2, width=W, height=H, seed=1)
    for style, params in (("contrast", {"c": 2.5}), ("cel", {})):
        image, pixels = quick_restyle_pixels(buf, style=style, **params)
        np.testing.assert_array_equal(image, quick_restyle(buf, style=style, **params))
        assert pixels.shape == (H, W, 4) and pixels.dtype == np.uint8
        np.testing.assert_array_equal(pixels[..., :3], srgb8(image))
        assert (pixels[..., 3] == 255).all()
    odd = np.array([[-1.0, 0.0, 0.002, 0.5, 1.0, 7.0, np.nan, np.inf, -np.inf]] * 3, np.float32).T
    got = srgb8_rgba(mi.Float(odd.ravel()), 9, 1)
    np.testing.assert_array_equal(got[0, :, :3], srgb8(odd))
