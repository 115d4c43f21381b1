"""A rectangle as seen from a point: its solid angle, and directions towards it sampled uniformly
in solid angle (Urena, Fajardo and King, "An Area-Preserving Parametrization for Spherical
Rectangles", EGSR 2013), on Dr.Jit arrays, one point per lane.

Both work in the rectangle's own frame with the point at the origin: the rectangle is
[x0, x1] x [y0, y1] in the plane z = z0 (x0 < x1, y0 < y1, z0 < 0: the point sits on the +z side;
a caller whose point is on the other side flips its z axis). `solid_angle` sums two triangles by
Van Oosterom and Strackee's atan2 formula, accurate to float32 rounding of the result even where
the rectangle is small or far (the paper's sum of four angles minus 2 pi loses the digits there);
the sampler inverts the paper's angles in float64 (tests/kernel/test_portal.py checks its
uniformity from 0.7 sr down to 3e-9 sr).
"""
from __future__ import annotations

import math

from styletrace.gate import dr, mi

#: where 1 - h^2 is this close to 0, the paper takes the rectangle's far edge (its `eps`)
_EDGE = 1e-12
#: keeps the square roots of 1 - c^2 and 1 - h^2 away from 0 (the results are clamped after)
_TINY = 1e-300


def _triangle(a, b, c, la, lb, lc, num):
    """Solid angle of the triangle (a, b, c) seen from the origin, given the lengths of a, b, c and
    |a . (b x c)| (Van Oosterom and Strackee 1983)."""
    den = la * lb * lc + dr.dot(a, b) * lc + dr.dot(a, c) * lb + dr.dot(b, c) * la
    return 2.0 * dr.atan2(num, den)


def solid_angle(x0, x1, y0, y1, z0) -> mi.Float:
    """Solid angle of the rectangle [x0, x1] x [y0, y1] at z = z0 seen from the origin.

    Args:
        x0, x1, y0, y1, z0: mi.Float per lane (x0 <= x1, y0 <= y1; z0's sign is irrelevant).

    Returns:
        mi.Float, in steradians, in [0, 2 pi]; 0 where z0 is 0 and the origin is off the
        rectangle.
    """
    a = mi.Vector3f(x0, y0, z0)
    b = mi.Vector3f(x1, y0, z0)
    c = mi.Vector3f(x1, y1, z0)
    e = mi.Vector3f(x0, y1, z0)
    la, lb, lc, le = dr.norm(a), dr.norm(b), dr.norm(c), dr.norm(e)
    # both triangles' triple products are z0 times twice their projected area
    num = dr.abs(z0) * (x1 - x0) * (y1 - y0)
    return _triangle(a, b, c, la, lb, lc, num) + _triangle(a, c, e, la, lc, le, num)


def sample(x0, x1, y0, y1, z0, u: mi.Point2f) -> mi.Vector3f:
    """A point of the rectangle [x0, x1] x [y0, y1] at z = z0 (< 0), uniformly distributed in the
    solid angle it subtends at the origin (the paper's `SphQuadSample`), computed in float64.

    Args:
        x0, x1, y0, y1, z0: mi.Float per lane, x0 < x1, y0 < y1, z0 < 0.
        u: a uniform 2D sample per lane (mi.Point2f).

    Returns:
        mi.Vector3f: the point (xu, yv, z0), not normalized; not finite where the rectangle is
        seen edge-on (z0 = 0), which the caller rejects.
    """
    # float64: the inversion subtracts angles near pi/2 whose float32 rounding (about 1e-7 rad)
    # is a 1% error of the mapping at 3e-5 sr (a window 1 m wide 100 m away); in float64 the
    # float32 inputs and output are the only rounding left
    x0, x1, y0, y1, z0 = (mi.Float64(v) for v in (x0, x1, y0, y1, z0))
    ux, uy = mi.Float64(u.x), mi.Float64(u.y)
    # the normals of the four planes through the origin and the rectangle's edges
    n0 = dr.normalize(mi.Vector3d(0.0, z0, -y0))
    n1 = dr.normalize(mi.Vector3d(-z0, 0.0, x1))
    n2 = dr.normalize(mi.Vector3d(0.0, -z0, y1))
    n3 = dr.normalize(mi.Vector3d(z0, 0.0, -x0))
    # the spherical rectangle's interior angles (each pair of normals shares only its z part)
    g0 = dr.safe_acos(-n0.z * n1.z)
    g1 = dr.safe_acos(-n1.z * n2.z)
    g2 = dr.safe_acos(-n2.z * n3.z)
    g3 = dr.safe_acos(-n3.z * n0.z)
    b0, b1 = n0.z, n2.z
    k = 2.0 * math.pi - g2 - g3
    area = g0 + g1 - k
    # the x of the sampled point: the sub-rectangle [x0, xu] has solid angle u.x * area
    au = ux * area + k
    fu = (dr.cos(au) * b0 - b1) / dr.sin(au)
    cu = dr.clip(dr.copysign(1.0 / dr.sqrt(fu * fu + b0 * b0), fu), -1.0, 1.0)
    xu = dr.clip(-(cu * z0) / dr.sqrt(dr.maximum(1.0 - cu * cu, _TINY)), x0, x1)
    # its y: uniform in the cosine-weighted height along that column
    d = dr.sqrt(xu * xu + z0 * z0)
    h0 = y0 / dr.sqrt(d * d + y0 * y0)
    h1 = y1 / dr.sqrt(d * d + y1 * y1)
    hv = h0 + uy * (h1 - h0)
    hv2 = hv * hv
    yv = dr.select(hv2 < 1.0 - _EDGE, hv * d / dr.sqrt(dr.maximum(1.0 - hv2, _TINY)), y1)
    return mi.Vector3f(mi.Float(xu), mi.Float(yv), mi.Float(z0))


__all__ = ["solid_angle", "sample"]
