"""Building blocks of LLaT's conditional lifting (kernel/lifted_lines.py): half-vector transport
keeps the tilt h . n to 1e-6, reduces to the identity where nothing moves, and makes a reflected
auxiliary ray after a flat mirror the mirror image of the camera's; minimal rotation; the slope
metric; the priority composition of two overlapping line types (Eqs. 32 and 34) against Monte
Carlo."""
import numpy as np

from styletrace.gate import dr, mi
from styletrace.kernel import lifted_lines as ll

RNG = np.random.default_rng(11)


def unit(a):
    return a / np.linalg.norm(a, axis=1, keepdims=True)


def vec(a):
    return mi.Vector3f(*np.ascontiguousarray(a.T.astype(np.float32)))


def test_transport_keeps_the_tilt_through_many_vertices():
    n_lanes = 2000
    n = unit(RNG.normal(size=(n_lanes, 3)))
    v = unit(RNG.normal(size=(n_lanes, 3)))
    v[(v * n).sum(1) > 0] *= -1                          # v arrives at the surface
    h = unit(n + 0.4 * RNG.normal(size=(n_lanes, 3)))
    h[(h * n).sum(1) < 0] *= -1
    c0 = (h * n).sum(1)
    H, N, V = vec(h), vec(n), vec(v)
    for _ in range(10):                                 # ten vertices of curved geometry in a row
        n2 = unit(np.array(N).T + 0.3 * RNG.normal(size=(n_lanes, 3)))
        v2 = unit(np.array(V).T + 0.2 * RNG.normal(size=(n_lanes, 3)))
        N2, V2 = vec(n2), vec(v2)
        H = ll.transport_half_vector(H, N, V, N2, V2)
        N, V = N2, V2
        c = np.array(dr.dot(H, N), dtype=np.float64)
        assert np.abs(c - c0).max() < 1e-6
        assert np.abs(np.array(dr.norm(H)) - 1).max() < 1e-6


def test_transport_is_the_identity_where_nothing_moves():
    n = unit(RNG.normal(size=(100, 3)))
    v = unit(RNG.normal(size=(100, 3)))
    h = unit(n + 0.5 * RNG.normal(size=(100, 3)))
    out = np.array(ll.transport_half_vector(vec(h), vec(n), vec(v), vec(n), vec(v))).T
    np.testing.assert_allclose(out, h, atol=2e-6)


def test_after_a_flat_mirror_the_auxiliary_reflects_like_the_mirrored_camera():
    """Flat mirror, perfectly specular base (h = n): the transported h is n at every auxiliary
    vertex, so the auxiliary ray leaves as the mirror image of its camera ray (the special case
    the paper notes)."""
    n = np.tile([[0.0, 0.0, 1.0]], (50, 1))
    v = unit(np.c_[RNG.normal(size=(50, 2)) * 0.3, -np.ones(50)])
    v2 = unit(v + 0.05 * RNG.normal(size=(50, 3)))
    h2 = ll.transport_half_vector(vec(n), vec(n), vec(v), vec(n), vec(v2))
    d2 = np.array(ll.reflect(vec(v2), h2)).T
    np.testing.assert_allclose(d2, v2 * [1, 1, -1], atol=1e-6)


def test_refraction_obeys_snell():
    n = np.tile([[0.0, 0.0, 1.0]], (50, 1))
    v = unit(np.c_[RNG.normal(size=(50, 2)) * 0.5, -np.ones(50)])
    d, ok = ll.refract(vec(v), vec(n), mi.Float(1.0 / 1.5))
    d = np.array(d).T
    assert np.array(ok).all()
    sin_i = np.linalg.norm(v[:, :2], axis=1)
    sin_t = np.linalg.norm(d[:, :2], axis=1)
    np.testing.assert_allclose(sin_t, sin_i / 1.5, atol=1e-6)
    assert (d[:, 2] < 0).all()


def test_minimal_rotation_takes_n_to_n2_and_keeps_angles():
    n = unit(RNG.normal(size=(200, 3)))
    n2 = unit(n + 0.5 * RNG.normal(size=(200, 3)))
    w = unit(RNG.normal(size=(200, 3)))
    np.testing.assert_allclose(
        np.array(ll.minimal_rotation(vec(n), vec(n2), vec(n))).T, n2, atol=2e-6
    )
    w2 = np.array(ll.minimal_rotation(vec(n), vec(n2), vec(w))).T
    np.testing.assert_allclose((w2 * n2).sum(1), (w * n).sum(1), atol=2e-6)
    axis = np.cross(n, n2)                                   # the axis itself does not move
    a2 = np.array(ll.minimal_rotation(vec(n), vec(n2), vec(axis))).T
    np.testing.assert_allclose(a2, axis, atol=2e-6)


def test_slope_metric_in_pixels():
    """A pair 0.5 px apart fires iff |df| / 0.5 >= t."""
    su = mi.Point2f(np.zeros(4, np.float32), np.zeros(4, np.float32))
    sv = mi.Point2f(np.full(4, 0.3, np.float32), np.full(4, 0.4, np.float32))
    fu = mi.Float(np.zeros(4, np.float32))
    fv = mi.Float(np.array([0.9, 1.1, -1.1, 0.0], np.float32))
    assert np.array(ll.fires(fu, fv, su, sv, 2.0)).tolist() == [False, True, True, False]


def test_two_overlapping_line_types_compose_by_priority():
    """Type A (priority 0, red) fires on a pair with probability pa, type B (priority 1, blue)
    with pb, independently; a type draws with w_i = (1 - p_i)^n_i over its n_i metric samples.
    Where both fire the red colour wins; the sample mean of Eq. 34's estimator matches Eq. 32
    within 4 standard errors."""
    pa, pb, na, nb = 0.05, 0.08, 12, 16
    L, ca, cb = np.array([0.5, 0.5, 0.5]), np.array([1.0, 0.0, 0.0]), np.array([0.0, 0.0, 1.0])
    N = 200_000
    fa = (RNG.random((N, na)) < pa).any(axis=1)
    fb = (RNG.random((N, nb)) < pb).any(axis=1)
    out = ll.compose_sample([fa[:, None], fb[:, None]], [ca, cb], L[None])
    both = fa & fb
    assert both.sum() > 1000 and np.all(out[both] == ca)
    wa, wb = (1 - pa) ** na, (1 - pb) ** nb
    want = ll.compose_expected([wa, wb], [ca, cb], L)
    err = out.std(axis=0) / np.sqrt(N)
    assert np.all(np.abs(out.mean(axis=0) - want) < 4 * err + 1e-12)
    # and the order matters: the other priority gives another mean (not within the error)
    other = ll.compose_expected([wb, wa], [cb, ca], L)
    assert np.any(np.abs(out.mean(axis=0) - other) > 10 * err)
