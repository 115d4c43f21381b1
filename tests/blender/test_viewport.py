"""The viewport's progressive session (`viewport.ViewportSession`, an adapter around the one
progressive schedule), driven step by step under a still clock: a denoised draft, then F12's
passes, whose images converge to F12's image of the same seed (equal after the last pass; before it,
the error shrinks as the variance of the passes left predicts); a style change restyles the recorded
buffer with no new pass into F12's image with the new value; a drag never waits for a pass. With
Denoise on, the passes are shown through F12's finisher: the last image is F12's denoised image, the
ones before it are denoised too, each closer to it than its raw pass and than the image before, and
a style change restyles the buffer F12's Record buffer keeps (Denoise expectation) or starts new
passes (Denoise image)."""
import time

import bpy
import numpy as np
import pytest
import scenes as S
from test_restyle import pixels

from styletrace.blender import camera, restyle
from styletrace.blender.viewport import REST_S, TURNS, Viewport
from styletrace.lookdev.slider import quick_restyle
from styletrace.progressive.rules import draft_size

SPP, PASS_SPP, SEED = 16, 4, 3
SETTINGS = dict(style="cel", inner_samples="4", denoise="off")


def still() -> float:
    """A clock that stands still: every denoising looks free, so the schedule denoises at every
    pass it may (`rules.denoise_now`), whatever this machine's speed."""
    return 0.0


def drive(vp: Viewport) -> None:
    """Run the viewport's session step by step to its end, in this thread."""
    s = vp.session
    while not s.done:
        s.schedule.step()
    assert s.error is None


def run_viewport(size=32, **settings):
    """The viewport's session on the room at `size`, driven to its end: (the viewport, the
    settings, [(label, image)] of every image it showed)."""
    S.room(size)
    st = bpy.context.scene.styletrace
    st.spp, st.pass_spp, st.seed = SPP, PASS_SPP, SEED
    for k, v in {**SETTINGS, **settings}.items():
        setattr(st, k, v)
    images = []
    vp = Viewport(start=False, clock=still)
    dg = bpy.context.evaluated_depsgraph_get()
    vp.set_sensor(camera.sensor(dg.scene_eval, SPP))  # the view through the scene camera
    vp.update(dg, st)
    s = vp.session
    s.on_image = lambda: images.append(s.latest()[::-1])
    drive(vp)
    return vp, st, images


def test_passes_converge_to_f12(tmp_path):
    # independent samples: the predicted spread below reads the Variance pass, exact only for them
    vp, st, images = run_viewport(sampler="independent")
    labels = [label for label, _ in images]
    print("images:", labels)
    assert labels[0].startswith("draft, denoised") and images[0][1].shape[:2] == draft_size(32, 32)
    assert labels[1:] == [f"pass {k}/4, {4 * k} spp" for k in range(1, 5)]
    f12 = S.styletrace(str(tmp_path / "f12.exr"), SPP, seed=SEED, pass_spp=PASS_SPP, aovs=True,
                       sampler="independent", **SETTINGS)
    final = images[-1][1]
    np.testing.assert_allclose(final, f12["Combined"][..., :3], rtol=1e-6, atol=1e-7)
    # pass k's image is the mean of k of the K passes: its difference to the final image has
    # variance sigma^2 (1/k - 1/K), sigma^2 = K * (the Variance pass, the final pixel's variance)
    var = f12["Variance"].astype(np.float64)
    errors = []
    for k, (_, img) in enumerate(images[1:-1], start=1):
        d2 = (img.astype(np.float64) - final) ** 2
        predicted = var * (4 / k - 1)
        # the sum's standard error from the pixels' own spread
        z = (d2.sum() - predicted.sum()) / (np.sqrt(d2.size) * (d2 - predicted).std())
        errors.append(d2.mean())
        print(f"pass {k}: mean squared error {d2.mean():.3e}, predicted {predicted.mean():.3e}, "
              f"z {z:.2f}")
        assert abs(z) < 4
    assert errors == sorted(errors, reverse=True)
    vp.close()


def test_a_drag_restyles_each_value_without_a_pass_and_rests_at_f12s_image(tmp_path):
    """A slider dragged through several values: each is shown at once, restyled at one point per
    pixel (`lookdev.slider`) with no new pass; at rest (`Viewport.settle`, which the timer of
    REST_S calls in Blender) the whole buffer is restyled: a fresh F12 with the last value."""
    vp, st, images = run_viewport()
    s = vp.session
    passes = s.passes_run
    for levels in ("0.1,0.5", "0.12,0.52", "0.14,0.55", "0.15,0.6", "0.1,0.5"):
        st.params.cel__levels = levels
        entry = vp.update(bpy.context.evaluated_depsgraph_get(), st)
        print(f"{levels}: restyle {entry['restyle_s'] * 1000:.1f} ms "
              f"({entry['seconds'] * 1000:.1f} ms the update)")
        assert entry["kind"] == "restyle" and vp.session is s and s.done
        assert s.latest()[1].startswith("restyled at one point per pixel")
        # each pixel shows its first camera sample's value with the new levels
        np.testing.assert_allclose(s.latest()[0],
                                   quick_restyle(s.buffer, style="cel", levels=levels),
                                   rtol=1e-6, atol=1e-7)
    assert s.passes_run == passes  # no new trace
    rest = vp.settle()
    print(f"at rest: {rest * 1000:.1f} ms")
    assert s.latest()[1].startswith("restyled, ") and s.passes_run == passes
    assert vp.settle() is None  # nothing left to rest
    fresh = S.styletrace(str(tmp_path / "fresh.exr"), SPP, seed=SEED, pass_spp=PASS_SPP,
                         aovs=False, **SETTINGS)["Combined"][..., :3]
    np.testing.assert_allclose(s.latest()[0], fresh, rtol=1e-4, atol=1e-5)
    vp.close()


def test_the_rest_timer_restyles_the_whole_buffer():
    """Without `settle`, the timer restyles the whole buffer REST_S after the last value."""
    vp, st, images = run_viewport()
    s = vp.session
    st.params.cel__levels = "0.12,0.52"
    vp.update(bpy.context.evaluated_depsgraph_get(), st)
    version = s.version
    deadline = time.perf_counter() + REST_S + 10.0
    while s.version == version and time.perf_counter() < deadline:
        time.sleep(0.01)
    assert s.latest()[1].startswith("restyled, ")
    vp.close()


def test_a_drag_never_waits_for_a_pass():
    """While a step of any view's schedule holds Dr.Jit (`TURNS`), a dragged value does not wait
    for it (Blender's UI thread must not freeze): the restyle returns at once, busy, and the next
    image shows the new value."""
    vp, st, _ = run_viewport()
    s = vp.session
    assert TURNS.acquire(wait=False)  # a pass of another view holds it
    try:
        st.params.cel__levels = "0.12,0.52"
        entry = vp.update(bpy.context.evaluated_depsgraph_get(), st)
        assert entry["kind"] == "restyle" and entry["restyle_s"] == 0.0  # busy: not waited
        assert s.style == vp.values["style"]  # kept: the next image shows it
    finally:
        TURNS.release()
    assert vp.settle() is not None and s.latest()[1].startswith("restyled, ")
    vp.close()


@pytest.mark.parametrize("method", ["expectation", "auto"])
def test_denoised_passes_end_at_f12s_denoised_image(method, tmp_path):
    vp, st, images = run_viewport(denoise=method)
    s = vp.session
    assert s.spp_done == SPP
    labels = [label for label, _ in images]
    print("images:", labels)
    # passes of 4 camera samples: no quick preview (`rules.quick_serves`); F12's finisher on the
    # passes so far after 4 and 8 camera samples (`rules.worth_showing`), then on all of them
    assert labels[1:] == ["pass 1/4, 4 spp, denoised", "pass 2/4, 8 spp, denoised",
                          "pass 4/4, 16 spp, denoised"]
    out = S.styletrace(str(tmp_path / "f12.exr"), SPP, seed=SEED, pass_spp=PASS_SPP,
                       **{**SETTINGS, "denoise": method})
    f12, noisy = out["Combined"][..., :3], out["Noisy"][..., :3]
    # the same finisher on the same samples (same scene, seed, kernels and OIDN filter); F12's
    # passes grow (`f12.job`) where the viewport's stay even, so the sums round differently
    np.testing.assert_allclose(images[-1][1], f12, rtol=1e-5, atol=1e-6)
    vp.close()
    # the undenoised passes of the same run: Denoise off with the firefly control a denoised
    # render gets (their last image is F12's Noisy pass); each image shown is closer to the final
    # image than the raw pass it was made from, and than the image before it
    plain, _, plain_images = run_viewport(denoise="off", firefly="on")
    np.testing.assert_allclose(plain_images[-1][1], noisy, rtol=1e-5, atol=1e-6)
    by_label = dict(plain_images)
    errors = []
    for label, img in images[1:-1]:
        raw = by_label[label.removesuffix(", denoised")]
        err, raw_err = (float(((a - b) ** 2).mean()) for a, b in ((img, f12), (raw, f12)))
        print(f"{label}: mean squared error to the final image {err:.3e}, undenoised {raw_err:.3e}")
        assert err < raw_err
        errors.append(err)
    assert errors == sorted(errors, reverse=True)
    plain.close()


def defaults_session(seed: int, size: int = 64) -> list[tuple[str, np.ndarray]]:
    """(label, image) of the viewport's session on the interior at the add-on's defaults (cel,
    Samples 16, Denoise auto) with `seed`."""
    S.interior(size)
    st = bpy.context.scene.styletrace
    # the suite's environment makes Denoise default to off (tests/conftest.py): the add-on's own
    # default is auto
    st.style, st.seed, st.denoise = "cel", seed, "auto"
    vp = Viewport(start=False, clock=still)
    dg = bpy.context.evaluated_depsgraph_get()
    vp.set_sensor(camera.sensor(dg.scene_eval, st.samples))
    images = []
    vp.on_image = lambda: images.append(vp.session.latest()[::-1])
    vp.update(dg, st)
    drive(vp)
    vp.close()
    return images


def test_each_viewport_image_is_no_noisier_than_the_one_before():
    """The interior lit through a window at the defaults, two seeds: along the full-size images
    both sessions showed (the previews after the passes the schedule picked, then F12's image),
    the noise between the seeds never grows. The draft (a smaller image) is left out. The noise of
    an image: the mean squared difference of the two seeds' images in sRGB; a later one may exceed
    an earlier one by at most 3 standard errors of the difference, from 8 x 8 blocks (denoised
    pixels are correlated, so single pixels would understate it)."""
    from styletrace.measures import srgb
    a, b = (dict(defaults_session(seed)) for seed in (1, 2))
    labels = [label for label in a if label in b and not label.startswith("draft")]
    print("images:", list(a), list(b))
    assert len(labels) >= 2 and labels[-1] == "pass 4/4, 4 spp, denoised"
    d2 = [(srgb(a[k]) - srgb(b[k])) ** 2 for k in labels]
    for k in range(1, len(labels)):
        diff = S.blocks((d2[k] - d2[k - 1]).mean(-1), 8).ravel()
        se = diff.std(ddof=1) / np.sqrt(diff.size)
        print(f"{labels[k - 1]} -> {labels[k]}: noise {d2[k - 1].mean():.3e} -> "
              f"{d2[k].mean():.3e} (z {diff.mean() / se:.2f})")
        assert diff.mean() <= 3 * se


def test_style_change_with_denoise_expectation_restyles_f12s_recorded_buffer(tmp_path):
    vp, st, images = run_viewport(denoise="expectation")
    s = vp.session
    passes, levels = s.passes_run, st.params.cel__levels
    st.params.cel__levels = "0.1,0.5"
    entry = vp.update(bpy.context.evaluated_depsgraph_get(), st)
    print(f"restyle of the denoised buffer: {entry['restyle_s'] * 1000:.1f} ms")
    assert entry["kind"] == "restyle" and vp.session is s and s.passes_run == passes
    assert s.buffer.header["denoise"]["method"] == "expectation"
    vp.settle()  # the drag's rest: the whole denoised buffer restyled
    shown = s.latest()[0]
    vp.close()
    # F12 with Record buffer and the same settings, then Blender's restyle of the same change
    st.params.cel__levels = levels
    S.styletrace(str(tmp_path / "recorded.exr"), SPP, seed=SEED, pass_spp=PASS_SPP,
                 record_buffer=True, **{**SETTINGS, "denoise": "expectation"})
    st.params.cel__levels = "0.1,0.5"  # the update callback restyles
    np.testing.assert_array_equal(shown, pixels(bpy.data.images[restyle.IMAGE]))
    st.record_buffer = False


def test_style_change_with_denoise_image_starts_new_passes():
    vp, st, images = run_viewport(denoise="image")
    s = vp.session
    assert images[-1][0] == "pass 4/4, 16 spp, denoised" and s.buffer is None
    st.params.cel__levels = "0.1,0.5"
    entry = vp.update(bpy.context.evaluated_depsgraph_get(), st)
    assert entry["kind"] == "settings" and vp.session is not s
    vp.close()


def test_loading_a_file_frees_every_viewport():
    """Blender drops the old file's engines on a load without their `__del__` reaching `free`; the
    add-on's `load_pre` handler stops and forgets every viewport."""
    from styletrace.blender import viewport_hooks

    vp, _, _ = run_viewport()
    key = -1  # a key no engine has
    viewport_hooks.VIEWS[key] = vp
    bpy.ops.wm.read_factory_settings(use_empty=True)
    assert key not in viewport_hooks.VIEWS and vp.session is None
    assert viewport_hooks.free_all in bpy.app.handlers.load_pre  # kept across the load
