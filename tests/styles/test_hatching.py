import itertools

import numpy as np
import pytest

from styletrace.gate import mi
from styletrace.styles import create
from styletrace.styles.hatching import active_sets, hatch_mask, plane_normals

from .support import point, rejects, rejects_unknown, run, vertex


def brute_force(p, u, normals, spacing, thickness, u_min, u_max):
    """Line test by scanning the planes k*spacing near each point, float64; also returns a 'too
    close to call' flag for points within float32 noise of a slab edge or of a change of m."""
    sets = len(normals)
    x = 1 - np.clip((u - u_min) / (u_max - u_min), 0, 1)
    m = np.floor(x * sets + 0.5)
    hit = np.zeros(len(p), bool)
    ambiguous = np.abs(x * sets + 0.5 - np.round(x * sets + 0.5)) < 1e-4
    for j, nj in enumerate(normals):
        s = p @ np.asarray(nj)
        k0 = np.floor(s / spacing)
        dist = np.min([np.abs(s - (k0 + dk) * spacing) for dk in (-1, 0, 1, 2)], axis=0)
        hit |= (dist < thickness / 2) & (j < m)
        ambiguous |= (np.abs(dist - thickness / 2) < 1e-5) & (j < m)
    return hit, ambiguous


@pytest.mark.parametrize("sets", [1, 2, 3, 5])
def test_mask_matches_brute_force(sets):
    rng = np.random.default_rng(10 + sets)
    N = 4000
    p = rng.uniform(-1.0, 1.0, size=(N, 3)).astype(np.float32)
    u = rng.uniform(-0.1, 1.1, size=N).astype(np.float32)
    normals = plane_normals((0.2, -0.3, 0.9), (0, 1, 0), sets, 30.0)
    spacing, thickness = 0.07, 0.025
    got = np.array(hatch_mask(point(p), mi.Float(u), normals, spacing, thickness, (0.05, 0.9)))
    want, amb = brute_force(
        p.astype(np.float64), u.astype(np.float64), normals, spacing, thickness, 0.05, 0.9
    )
    assert amb.sum() < N // 50
    np.testing.assert_array_equal(got[~amb], want[~amb])
    assert 0 < want.sum() < N


def test_plane_normals_contain_view_direction():
    view = np.array([0.3, -0.5, 0.8])
    view /= np.linalg.norm(view)
    for sets in (1, 2, 3, 4, 8):
        ns = np.array(plane_normals(tuple(view), (0, 1, 0), sets, 45.0))
        np.testing.assert_allclose(np.linalg.norm(ns, axis=1), 1.0, atol=1e-12)
        np.testing.assert_allclose(ns @ view, 0.0, atol=1e-12)
        for a, b in itertools.combinations(range(sets), 2):
            c = np.cross(ns[a], ns[b])
            # n_a x n_b parallel to view
            np.testing.assert_allclose(np.cross(c, view), 0.0, atol=1e-12)
            np.testing.assert_allclose(
                abs(ns[a] @ ns[b]), abs(np.cos((b - a) * np.pi / sets)), atol=1e-12
            )
    # up parallel to view still gives a valid frame
    ns = np.array(plane_normals((0, 1, 0), (0, 1, 0), 2, 0.0))
    np.testing.assert_allclose(ns @ np.array([0, 1, 0]), 0.0, atol=1e-12)


def test_active_sets_ends_and_rounding():
    u = mi.Float([0.0, 0.05, 0.9, 2.0, 0.475])
    m = np.array(active_sets(u, 4, 0.05, 0.9))
    # u_min -> all 4 sets, u_max -> none; midway: 0.5 * 4 + 0.5 -> 2
    np.testing.assert_array_equal(m, [4, 4, 0, 0, 2])


def test_apply_colours_and_thresholds():
    h = create("hatching", sets=1, spacing=0.1, angle=0.0, thickness=0.02)
    # default camera: view +z, up +y -> the single set has normal e1 = up x view = +x
    np.testing.assert_allclose(h.normals[0], (1, 0, 0), atol=1e-12)
    p = [(0.005, 0.3, 0.2), (0.05, 0.3, 0.2), (0.205, -1, 4), (0.005, 0, 0)]
    I = [(0, 0, 0), (0, 0, 0), (0.1, 0.1, 0.1), (1, 1, 1)]   # dark, dark, dark, bright (no sets)
    out = run(h, I, vertex(p=p))
    line, bg = np.array(h.line_color), np.array(h.background)
    np.testing.assert_allclose(out, [line, bg, line, bg], atol=1e-6)


def test_prepare_reads_camera():
    scene = mi.load_dict(
        {
            "type": "scene",
            "sensor": {
                "type": "perspective",
                "to_world": mi.ScalarTransform4f().look_at(
                    origin=[0, 0, 5], target=[0, 0, 0], up=[0, 1, 0]
                ),
            },
        }
    )
    h = create("hatching", sets=3)
    h.prepare(scene)
    np.testing.assert_allclose(h.view, (0, 0, -1), atol=1e-6)
    np.testing.assert_allclose(np.array(h.normals) @ np.array([0, 0, -1.0]), 0, atol=1e-6)


def test_parameters_and_defaults():
    h = create("hatching")
    # spacing is auto: lines spacing_px = 8 pixels apart, 0.3 * 8 thick; a given spacing is in scene
    # units
    assert (
        h.sets == 3
        and h.spacing is None
        and h.spacing_px == 8
        and abs(h.line_thickness - 2.4) < 1e-12
    )
    assert abs(create("hatching", spacing=0.1).line_thickness - 0.03) < 1e-12
    assert abs(create("hatching", spacing_px=20).line_thickness - 6.0) < 1e-12
    msg = rejects("hatching", "thickness", 8.5)          # >= default spacing_px 8
    assert "spacing_px" in msg
    rejects("hatching", "sets", 0)
    rejects("hatching", "sets", 9)
    rejects("hatching", "sets", 2.5)
    rejects("hatching", "spacing", 0.0)
    msg = rejects("hatching", "thickness", 0.05, spacing=0.04)          # >= spacing 0.04
    assert "spacing" in msg
    msg = rejects("hatching", "u_max", 0.01, u_min=0.05)
    assert "u_min" in msg
    rejects("hatching", "line_color", "#12345")
    rejects_unknown("hatching")
