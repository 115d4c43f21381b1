"""The local inverse of the mirror-anchor map: linear moving least squares (LLaT, Eq. 35,
supplement S2.5).

Reference: "Lifting Lines and Tone: Image-space Stylization in Path-space", Rex West, Sayan
Mukherjee and Yonghao Yue (ACM TOG 45(4), 2026); linear MLS after "Image Deformation Using Moving
Least Squares", Scott Schaefer, Travis McPhail and Joe Warren (2006).

Given candidate anchor vertices p_i (world points) with their image coordinates s_i and a query
point x reached along the incoming direction d:
    chart:  the plane through x with normal n = -d/|d|; e1, e2 an orthonormal basis of it;
            q_i = ((p_i - x) . e1, (p_i - x) . e2) / sigma,  sigma = mean_i |q_i| (before scaling)
    weights w_i = exp(-|q_i|^2)            (Gaussian, sigma = mean candidate distance)
    fit     min_{A,b} sum_i w_i |A q_i + b - s_i|^2,   s(x) = b   (x is the chart's origin)
The two 3x3 normal equations share one matrix M = sum_i w_i (1, q_i)(1, q_i)^T; b = first row of
M^-1 (sum_i w_i s_i (1, q_i)). Working in sigma units keeps M's scale independent of the scene's.

Fallbacks (supplement S2.5's chain), each taken where the one before it is not trusted:
    MLS      M well conditioned (det M / (sum w)^3 > COND) and the weighted centroid of the q_i
             within CENTRE sigma of the query: the fit interpolates rather than extrapolates;
    affine   the same fit with w_i = 1 (all candidates count equally), M well conditioned;
    nearest  the s_i of the candidate closest in the chart;
    first    the caller's first-edge coordinate.
All functions here run on Dr.Jit arrays over lanes, the candidates unrolled as Python lists (their
count is small and fixed), so no gather and no loop is traced.
"""
from __future__ import annotations

from styletrace.gate import dr, mi

#: method codes, as the `coordinate` style and the docs report them
CLOSED_PIXEL, CLOSED_DELTA, MLS, AFFINE, NEAREST, FIRST = 0, 1, 2, 3, 4, 5
METHOD_NAMES = ("pixel", "all-delta", "mls", "affine", "nearest", "first-edge")

#: det M / (sum w)^3 below this: the candidates are (nearly) collinear in the chart. For 3
#: candidates at unit distance spread evenly the ratio is 27/4 / 27 = 0.25; 1e-4 refuses only
#: near-degenerate layouts.
COND = 1e-4
#: the weighted centroid farther than this many sigma from the query: the fit would extrapolate
CENTRE = 0.75


def _solve_b(sums, ss):
    """b = e_0^T M^-1 r for the symmetric 3x3 M of `sums` = (S, Sx, Sy, Sxx, Sxy, Syy) and
    right-hand sides `ss` = [(R, Rx, Ry) per output coordinate]; also det M. Cramer's rule on the
    first unknown."""
    S, Sx, Sy, Sxx, Sxy, Syy = sums
    c00 = Sxx * Syy - Sxy * Sxy   # cofactors of the first column
    c01 = Sxy * Sy - Sx * Syy
    c02 = Sx * Sxy - Sxx * Sy
    det = S * c00 + Sx * c01 + Sy * c02
    inv = dr.rcp(dr.select(det != 0, det, 1.0))
    out = [(R * c00 + Rx * c01 + Ry * c02) * inv for R, Rx, Ry in ss]
    return out, det


def _sums(q, s, w, valid):
    S = Sx = Sy = Sxx = Sxy = Syy = mi.Float(0.0)
    Ru = [mi.Float(0.0)] * 3
    Rv = [mi.Float(0.0)] * 3
    for (qx, qy), (su, sv), wi, ok in zip(q, s, w, valid):
        wi = dr.select(ok, wi, 0.0)
        S, Sx, Sy = S + wi, Sx + wi * qx, Sy + wi * qy
        Sxx, Sxy, Syy = Sxx + wi * qx * qx, Sxy + wi * qx * qy, Syy + wi * qy * qy
        Ru = [Ru[0] + wi * su, Ru[1] + wi * su * qx, Ru[2] + wi * su * qy]
        Rv = [Rv[0] + wi * sv, Rv[1] + wi * sv * qx, Rv[2] + wi * sv * qy]
    return (S, Sx, Sy, Sxx, Sxy, Syy), (Ru, Rv)


def plane_chart(x: mi.Point3f, d: mi.Vector3f):
    """An orthonormal basis (e1, e2) of the plane through x normal to -d (the incoming
    direction's chart)."""
    e1, e2 = mi.coordinate_system(dr.normalize(-d))
    return e1, e2


def invert(x: mi.Point3f, d: mi.Vector3f, points, coords, valid, first: mi.Point2f):
    """s(x) from the candidates (world `points`, image `coords` as (Float, Float), `valid` masks) by
    the chain MLS -> affine -> nearest -> `first`; returns (Point2f, method code UInt32)."""
    e1, e2 = plane_chart(x, d)
    raw = []
    for p in points:
        r = mi.Vector3f(p - x)
        raw.append((dr.dot(r, e1), dr.dot(r, e2)))
    count = mi.Float(0.0)
    total = mi.Float(0.0)
    for (a, b), ok in zip(raw, valid):
        count += dr.select(ok, 1.0, 0.0)
        total += dr.select(ok, dr.sqrt(a * a + b * b), 0.0)
    sigma = dr.maximum(total / dr.maximum(count, 1.0), 1e-12)
    inv = dr.rcp(sigma)
    q = [(a * inv, b * inv) for a, b in raw]
    r2 = [qx * qx + qy * qy for qx, qy in q]

    # nearest candidate
    best = mi.Float(dr.inf)
    near = mi.Point2f(first)
    for (su, sv), d2, ok in zip(coords, r2, valid):
        closer = ok & (d2 < best)
        best = dr.select(closer, d2, best)
        near = dr.select(closer, mi.Point2f(su, sv), near)

    def fit(w):
        sums, (Ru, Rv) = _sums(q, coords, w, valid)
        (bu, bv), det = _solve_b(sums, [Ru, Rv])
        S = dr.maximum(sums[0], 1e-30)
        good = (count >= 3) & (det > COND * S * S * S) & dr.isfinite(bu) & dr.isfinite(bv)
        centre = dr.sqrt(dr.square(sums[1]) + dr.square(sums[2])) / S
        return mi.Point2f(bu, bv), good, centre

    s_mls, ok_mls, centre = fit([dr.exp(-d2) for d2 in r2])
    ok_mls &= centre < CENTRE
    s_aff, ok_aff, _ = fit([mi.Float(1.0)] * len(q))
    has = count >= 1
    s = dr.select(ok_mls, s_mls, dr.select(ok_aff, s_aff, dr.select(has, near, first)))
    method = dr.select(
        ok_mls,
        mi.UInt32(MLS),
        dr.select(ok_aff, mi.UInt32(AFFINE), dr.select(has, mi.UInt32(NEAREST), mi.UInt32(FIRST))),
    )
    return s, method
