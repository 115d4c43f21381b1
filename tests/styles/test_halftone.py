import itertools
import math

import numpy as np

from styletrace.gate import mi
from styletrace.styles import create
from styletrace.styles.halftone import dot_radius, halftone_mask

from .support import point, rejects, rejects_unknown, run, vertex


def brute_force(p, u, spacing, r_max, u_min, u_max):
    """Nearest of the 27 grid points around floor(p/d), float64; with a 'too close to call' flag."""
    r = (1 - np.clip((u - u_min) / (u_max - u_min), 0, 1)) * r_max
    base = np.floor(p / spacing)
    best = np.full(len(p), np.inf)
    for off in itertools.product((-1, 0, 1), repeat=3):
        g = (base + np.array(off)) * spacing
        best = np.minimum(best, np.linalg.norm(p - g, axis=1))
    return best < r, np.abs(best - r) < 1e-5


def test_mask_matches_brute_force():
    rng = np.random.default_rng(20)
    N = 5000
    p = rng.uniform(-2.0, 2.0, size=(N, 3)).astype(np.float32)
    u = rng.uniform(-0.1, 1.1, size=N).astype(np.float32)
    spacing, r_max = 0.13, 0.75 * 0.5 * math.sqrt(3) * 0.13
    got = np.array(halftone_mask(point(p), mi.Float(u), spacing, r_max, 0.05, 0.9))
    want, amb = brute_force(p.astype(np.float64), u.astype(np.float64), spacing, r_max, 0.05, 0.9)
    assert amb.sum() < N // 100
    np.testing.assert_array_equal(got[~amb], want[~amb])
    assert 0.05 * N < want.sum() < 0.95 * N


def test_radius_mapping():
    r = np.array(dot_radius(mi.Float([0.0, 0.05, 0.475, 0.9, 3.0]), 2.0, 0.05, 0.9))
    np.testing.assert_allclose(r, [2.0, 2.0, 1.0, 0.0, 0.0], atol=1e-6)


def test_apply_hand_values():
    h = create("halftone", spacing=1.0, max_radius_fraction=1.0)   # r_max = sqrt(3)/2
    dark, light = np.array(h.dark), np.array(h.light)
    # u = u_min: r = 0.866; u = 0.475: r = 0.433; u >= u_max: no dot even on a grid point
    p = [(0.1, 0.1, 0.1), (2.3, 0.0, 0.0), (2.6, 0.0, 0.0), (1.0, 1.0, 1.0), (0.5, 0.5, 0.45)]
    I = [(0.05,) * 3, (0.475,) * 3, (0.475,) * 3, (0.9,) * 3, (0.0,) * 3]
    out = run(h, I, vertex(p=p))
    # |(2.3,0,0)-(2,0,0)| = 0.3 < 0.433; |(2.6,0,0)-(3,0,0)| = 0.4 < 0.433; corner-ish point: 0.835
    # < 0.866
    np.testing.assert_allclose(out, [dark, dark, dark, light, dark], atol=1e-6)
    out = run(h, [(0.475,) * 3], vertex(p=[(2.45, 0, 0)]))          # 0.45 > 0.433
    np.testing.assert_allclose(out[0], light, atol=1e-6)


def test_parameters_and_defaults():
    h = create("halftone")
    # spacing is auto: a screen grid spacing_px = 8 pixels apart, radius up to 0.75 of half its
    # diagonal
    assert (
        h.spacing is None
        and h.spacing_px == 8
        and math.isclose(h.r_max, 0.75 * 0.5 * math.sqrt(2) * 8)
    )
    assert math.isclose(create("halftone", spacing=0.05).r_max, 0.75 * 0.5 * math.sqrt(3) * 0.05)
    rejects("halftone", "spacing", -1.0)
    rejects("halftone", "max_radius_fraction", 0.0)
    rejects("halftone", "max_radius_fraction", 1.5)
    msg = rejects("halftone", "u_max", 0.0, u_min=0.05)
    assert "u_min" in msg
    rejects("halftone", "dark", "red")
    rejects_unknown("halftone")
