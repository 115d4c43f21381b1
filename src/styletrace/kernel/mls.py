"""Linear moving least squares: the local inverse of LLaT's mirror-anchor map (LLaT Eq. 35, S2.5).

For candidate anchors p_i (world) with image coordinates s_i and a query x reached along d:
    chart  e1, e2 a basis of the plane through x normal to d; q_i = ((p_i - x).e1, (p_i - x).e2)
           / sigma, sigma = the candidates' mean distance from x in the chart
    fit    min_{A,b} sum_i w_i |A q_i + b - s_i|^2 with w_i = exp(-|q_i|^2); s(x) = b
Fallbacks, each where the one before is not trusted: MLS (M well conditioned, weighted centroid
within CENTRE sigma) -> affine (w_i = 1) -> nearest candidate -> the caller's first-edge
coordinate. Dr.Jit arrays over lanes, candidates unrolled as Python lists: no gather, no loop.
Design: docs/design/mirror_anchors.md.
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
    direction's chart).

    Args:
        x: the query point (the basis does not depend on it). d: the incoming direction.

    Returns:
        (e1, e2), mi.Vector3f each.
    """
    e1, e2 = mi.coordinate_system(dr.normalize(-d))
    return e1, e2


def invert(x: mi.Point3f, d: mi.Vector3f, points, coords, valid, first: mi.Point2f):
    """s(x) from the candidates by the chain MLS -> affine -> nearest -> `first`.

    Args:
        x, d: the query point (mi.Point3f) and its incoming direction (mi.Vector3f).
        points, coords, valid: per candidate its world point, image coordinate (Float, Float)
            and whether it counts (mi.Bool); Python lists of equal length.
        first: the caller's first-edge coordinate (mi.Point2f).

    Returns:
        (s mi.Point2f, method code mi.UInt32: MLS, AFFINE, NEAREST or FIRST).
    """
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
