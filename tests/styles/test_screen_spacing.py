"""Screen-space spacing of hatching and halftone (spacing_px, the default): lines and dots are
evenly spaced in pixels at every depth. Truth: points placed on the sensor's own rays through
known film positions (`sample_ray`), at depths 100x apart, and the pixel grid computed in numpy."""
import numpy as np
import pytest

from styletrace.gate import mi
from styletrace.styles import create

from .support import run, vertex

W = 100  # film width and height in pixels


def scene(fov=40.0):
    return mi.load_dict({"type": "scene", "sensor": {
        "type": "perspective", "fov": fov, "to_world": mi.ScalarTransform4f().look_at(
            origin=[3, 1, 4], target=[0, 0.5, 0], up=[0, 1, 0]),
        "film": {"type": "hdrfilm", "width": W, "height": W}}})


def points_at(sc, px, py, depth):
    """World points on the rays through film pixel offsets (px, py) from the centre, `depth`
    along each."""
    sensor = sc.sensors()[0]
    uv = mi.Point2f(np.float32(0.5 + np.asarray(px) / W), np.float32(0.5 + np.asarray(py) / W))
    ray, _ = sensor.sample_ray(mi.Float(0.0), mi.Float(0.5), uv, mi.Point2f(0.5, 0.5))
    o, d = np.array(ray.o).T, np.array(ray.d).T
    return o + depth * d


def pixel_dist(x, spacing):
    """Distance of x (pixels) to the nearest multiple of spacing."""
    return np.abs(x - np.round(x / spacing) * spacing)


@pytest.mark.parametrize("fov", [20.0, 60.0])
def test_hatching_lines_are_spacing_px_apart_at_every_depth(fov):
    sc = scene(fov)
    h = create("hatching", sets=1, angle=0.0, spacing_px=10.0, thickness=2.0, u_min=0.0, u_max=1.0)
    h.prepare(sc)
    # offsets along the film's x axis: the single set (angle 0) has lines across x, 10 px apart
    # none at exactly thickness / 2 from a line, where float rounding decides (31.0 drew a line on
    # cuda_ad_rgb and none on llvm_ad_rgb)
    px = np.array(
        [0.3, 0.8, 3.0, 5.0, 9.2, 10.5, 14.0, 19.4, -0.7, -10.2, -13.0, -20.9, 31.2, 40.6]
    )
    py = np.linspace(-30, 30, len(px))          # moving along a line does not change the result
    want = pixel_dist(px, 10.0) < 1.0
    assert want.any() and not want.all()
    line = np.array(h.line_color)
    for depth in (0.5, 5.0, 50.0):
        p = points_at(sc, px, py, depth)
        out = run(h, np.zeros((len(px), 3)), vertex(p=p))
        np.testing.assert_array_equal(
            np.all(np.abs(out - line) < 1e-6, axis=1), want, err_msg=f"depth {depth}"
        )


def test_world_spacing_still_available_and_depth_dependent_on_screen():
    sc = scene()
    h = create("hatching", sets=1, angle=0.0, spacing=0.02, thickness=0.004, u_min=0.0, u_max=1.0)
    h.prepare(sc)
    px = np.linspace(-40, 40, 401)
    masks = []
    for depth in (0.5, 50.0):
        out = run(h, np.zeros((len(px), 3)), vertex(p=points_at(sc, px, np.zeros_like(px), depth)))
        masks.append(np.all(np.abs(out - np.array(h.line_color)) < 1e-6, axis=1))
    # fixed world planes: the screen pattern changes with depth
    assert not np.array_equal(masks[0], masks[1])


def test_halftone_dots_on_a_screen_grid_at_every_depth():
    sc = scene()
    h = create("halftone", spacing_px=10.0, max_radius_fraction=0.5, u_min=0.0, u_max=1.0)
    h.prepare(sc)
    r = 0.5 * np.sqrt(2) / 2 * 10.0          # u <= u_min: the largest dots, 3.54 px
    rng = np.random.default_rng(3)
    px, py = rng.uniform(-35, 35, size=(2, 300))
    d = np.hypot(pixel_dist(px, 10.0), pixel_dist(py, 10.0))
    # leave out points within float32 noise of a dot's edge
    keep = np.abs(d - r) > 0.05
    px, py, want = px[keep], py[keep], d[keep] < r
    assert 0.1 < want.mean() < 0.9
    for depth in (0.5, 50.0):
        out = run(h, np.zeros((len(px), 3)), vertex(p=points_at(sc, px, py, depth)))
        np.testing.assert_array_equal(np.all(np.abs(out - np.array(h.dark)) < 1e-6, axis=1), want)


# Rendered: orthographic and thin-lens sensors. The sensor's own pixel size sets the spacing
# (Projection reads it from two of its rays); an orthographic sensor returns its one ray direction
# as an array of width 1, which the projection once indexed as two and crashed the render
# (IndexError inside mi.render).

R = 64  # rendered film width and height


def camera_scene(kind):
    sensor = {
        "type": kind,
        "film": {"type": "hdrfilm", "width": R, "height": R, "rfilter": {"type": "box"}},
        "to_world": mi.ScalarTransform4f().look_at(
            origin=[0, 0, 5], target=[0, 0, 0], up=[0, 1, 0]
        ),
    }
    # a view 2 x 3.7 units wide: a pixel is not one unit, nor the default 2/R
    if kind == "orthographic":
        sensor["to_world"] = sensor["to_world"] @ mi.ScalarTransform4f().scale([3.7, 3.7, 1.0])
    if kind == "thinlens":       # the wall in focus: its chief rays are the perspective ones
        sensor.update(fov=50.0, aperture_radius=0.05, focus_distance=5.0)
    return {
        "type": "scene",
        "sensor": sensor,
        "wall": {
            "type": "rectangle",
            "to_world": mi.ScalarTransform4f().scale([20.0, 20.0, 1.0]),
            "bsdf": {"type": "diffuse"},
        },
        "light": {"type": "constant"},
    }


def period(signal):
    """The dominant period (in samples) of a 1D signal, from the peak of its zero-padded
    spectrum."""
    s = np.asarray(signal, dtype=np.float64)
    pad = 1 << 14
    spectrum = np.abs(np.fft.rfft(s - s.mean(), pad))
    # leave out the lowest frequencies (periods over 2000 px)
    k = int(np.argmax(spectrum[8:])) + 8
    return pad / k


def dark(img):
    """1 where a pixel is mostly line/dot colour, 0 where background (both styles draw dark on
    light)."""
    return (img[..., :3].mean(axis=2) < 0.5).astype(np.float64)


@pytest.mark.parametrize("kind", ["orthographic", "thinlens"])
@pytest.mark.parametrize("spacing_px", [8.0, 6.0])
def test_rendered_hatching_period_is_spacing_px(kind, spacing_px):
    """One set (angle 0: lines across the image's x axis), every set drawn (u_max above any
    brightness)."""
    import styletrace
    img = styletrace.render(camera_scene(kind), style="hatching", spp=4, inner=1, sets=1, angle=0.0,
                            spacing_px=spacing_px, u_min=100.0, u_max=200.0)
    lines = dark(img)
    assert 0.15 < lines.mean() < 0.6, lines.mean()
    assert period(lines.mean(axis=0)) == pytest.approx(spacing_px, rel=0.03)
    assert np.ptp(lines.mean(axis=1)) < 0.2       # vertical lines: every row has the same coverage


@pytest.mark.parametrize("kind", ["orthographic", "thinlens"])
def test_rendered_halftone_grid_is_spacing_px(kind):
    import styletrace
    img = styletrace.render(camera_scene(kind), style="halftone", spp=4, inner=1, spacing_px=8.0,
                            max_radius_fraction=0.5, u_min=100.0, u_max=200.0)
    dots = dark(img)
    assert 0.1 < dots.mean() < 0.6, dots.mean()
    assert period(dots.mean(axis=0)) == pytest.approx(8.0, rel=0.03)
    assert period(dots.mean(axis=1)) == pytest.approx(8.0, rel=0.03)
