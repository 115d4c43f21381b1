"""Image coordinates of stylized vertices: LLaT's canonical lifting of tone (the mirror-anchor map;
"Lifting Lines and Tone", West, Mukherjee and Yue, ACM TOG 2026, Sections 5 and S2).

A vertex x at path depth k gets s (screen pixels from the image centre, as `Projection.pixels`):
    k = 0                          the pixel x is seen in (method "pixel");
    all-delta before x, pinhole    s0, the pixel of the camera ray's first hit ("all-delta");
    otherwise                      phi_k^-1(x) by linear MLS over anchor vertices (mls.py).
phi_k sends s to the depth-k vertex of the anchor path from s: from the lens centre, reflecting
about the geometric normal or refracting where the query transmitted. ANCHORS anchor paths start
at s0 + RING_OFFSETS per query; `ToneState` is what a path carries for them.
Design: docs/design/mirror_anchors.md.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

from styletrace.gate import dr, mi
from styletrace.kernel import mls
from styletrace.styles.base import projection

#: film offsets (pixels) of the anchors traced around a query's first-edge coordinate s0
RING_RADII = (2.0, 6.0, 18.0, 54.0)
RING_OFFSETS = ((0.0, 0.0),) + tuple(
    (r * math.cos(a), r * math.sin(a))
    for i, r in enumerate(RING_RADII)
    for a in (math.radians(22.5 * i + 90.0 * j) for j in range(4)))
ANCHORS = len(RING_OFFSETS)
#: branch bits are kept for depths below this (UInt32); deeper transmissions count as reflections
MAX_BITS = 32


@dataclass
class ToneState:
    """Carried along a path (a Dr.Jit PyTree): what the anchor search needs at its next
    stylized vertex."""
    key: mi.UInt32      # hash of the shape ids at depths 0..k-1
    bits: mi.UInt32     # bit j set: the path transmitted at depth j
    delta: mi.Bool      # every scattering at depths 0..k-1 was a delta event
    s0: mi.Point2f      # first-edge coordinate: the pixel of the camera ray's first hit


def has_aperture(sensor) -> bool:
    """Whether rays through one film point leave from different points for different
    lens samples.

    Args:
        sensor: the scene's sensor.

    Returns:
        bool.
    """
    import numpy as np

    ray, _ = sensor.sample_ray(
        mi.Float(0.0, 0.0),
        mi.Float(0.5, 0.5),
        mi.Point2f([0.5, 0.5], [0.5, 0.5]),
        mi.Point2f([0.05, 0.95], [0.05, 0.95]),
    )
    o = np.array(ray.o, dtype=np.float64).reshape(3, -1)
    if o.shape[1] < 2:   # the origin did not depend on the lens sample at all
        return False
    return bool(np.abs(o[:, 0] - o[:, 1]).max() > 1e-7 * (1.0 + np.abs(o).max()))


def shape_id(si) -> mi.UInt32:
    """The shape's registry index (a stable integer per shape within one scene).

    Args:
        si: the hits (an interaction with a `shape`).

    Returns:
        mi.UInt32.
    """
    return dr.reinterpret_array(mi.UInt32, si.shape)


def combine(key: mi.UInt32, sid: mi.UInt32) -> mi.UInt32:
    """Extend a prefix key by one shape (FNV-1a's multiply-xor step on the shape index).

    Args:
        key: the prefix key (mi.UInt32). sid: the shape index (`shape_id`).

    Returns:
        mi.UInt32.
    """
    return (key * mi.UInt32(16777619)) ^ (sid + 1)


class Tone:
    """Image coordinates for one scene's stylized vertices (built per traced kernel, like
    lines.Lines), through its first sensor.

    Args:
        scene: the scene, with a sensor.
    """

    def __init__(self, scene: mi.Scene):
        self.projection = projection(scene)
        sensor = scene.sensors()[0]
        self.sensor = sensor
        size = sensor.film().crop_size()
        self.width, self.height = float(size[0]), float(size[1])
        self.lens = has_aperture(sensor)

    def start(self, ray: mi.Ray3f, pi, active) -> ToneState:
        """The state of a camera ray reaching its first vertex: empty prefix, s0 = that
        vertex's pixel.

        Args:
            ray: the camera ray. pi: its first intersection (preliminary).
            active: the camera lanes (mi.Bool).

        Returns:
            ToneState.
        """
        x, y = self.projection.pixels(
            mi.Point3f(ray.o + ray.d * dr.select(active & pi.is_valid(), pi.t, 1.0))
        )
        return ToneState(
            key=mi.UInt32(2166136261), bits=mi.UInt32(0), delta=mi.Bool(True), s0=mi.Point2f(x, y)
        )

    def coordinate(self, scene: mi.Scene, si, ray: mi.Ray3f, depth, tone: ToneState | None, active):
        """(s, method) of the vertex `si`: its image coordinate and how it was found (module doc).

        Args:
            scene: the scene. si, ray: the vertex and the ray that reached it.
            depth: its path depth. tone: the ToneState the path carried there (None: a walk
                without one, whose s is the position's projection).
            active: the lanes at a stylized vertex (mi.Bool).

        Returns:
            (mi.Point2f, method code of mls, mi.UInt32).
        """
        px, py = self.projection.pixels(si.p)
        direct = mi.Point2f(px, py)
        # a walk that carries no tone state (participating media): the position's projection
        if tone is None:
            return direct, mi.UInt32(mls.CLOSED_PIXEL)
        depth = mi.UInt32(depth)
        first = depth == 0
        # the all-delta closed form holds for a pinhole (or orthographic) camera only: through a
        # lens the anchor (from the lens centre) and the sample's ray (from elsewhere on the lens)
        # part after the first vertex
        closed = first | (tone.delta & (not self.lens))
        s = dr.select(first, direct, tone.s0)
        method = dr.select(first, mi.UInt32(mls.CLOSED_PIXEL), mi.UInt32(mls.CLOSED_DELTA))
        need = active & ~closed
        pts, coords, valid = self.trace(scene, si, depth, tone, need)
        s_inv, m_inv = mls.invert(si.p, ray.d, pts, coords, valid, tone.s0)
        return dr.select(need, s_inv, s), dr.select(need, m_inv, method)

    def film_uv(self, x, y):
        """Film position (Mitsuba's [0,1]^2, x right, y down) of screen pixels from the centre, as
        `Projection.pixels` gives them (x towards the image's left, y up).

        Args:
            x, y: screen pixels (mi.Float or float).

        Returns:
            mi.Point2f.
        """
        return mi.Point2f(0.5 - x * (1.0 / self.width), 0.5 - y * (1.0 / self.height))

    def trace(self, scene: mi.Scene, si, depth: mi.UInt32, tone: ToneState, active):
        """The anchor paths from s0 + RING_OFFSETS to depth `depth`.

        Args:
            scene: the scene. si: the query vertex. depth: its path depth k (mi.UInt32).
            tone: the query's ToneState (s0, prefix key, branch bits). active: the lanes asked.

        Returns:
            (their depth-k points, their image coordinates, whether each is a candidate: same
            shapes along the way and at depth k), one entry per anchor.
        """
        coords = [(tone.s0.x + dx, tone.s0.y + dy) for dx, dy in RING_OFFSETS]
        rays = []
        for cx, cy in coords:
            ray, _ = self.sensor.sample_ray(mi.Float(0.0), mi.Float(0.5), self.film_uv(cx, cy),
                                            mi.Point2f(0.5, 0.5), active)
            rays.append(mi.Ray3f(ray))
        target = shape_id(si)
        ctx = mi.BSDFContext()
        ctx.type_mask = int(mi.BSDFFlags.Transmission)
        n = len(coords)
        state = (
            mi.UInt32(0),
            [mi.Bool(active) for _ in range(n)],
            rays,
            [mi.UInt32(2166136261) for _ in range(n)],
            [dr.zeros(mi.Point3f) for _ in range(n)],
            [mi.Bool(False) for _ in range(n)],
        )

        def cond(j, alive, rays, keys, pts, ok):
            out = mi.Bool(False)
            for a in alive:
                out |= a
            return out

        def body(j, alive, rays, keys, pts, ok):
            for m in range(n):
                a = alive[m]
                hit = scene.ray_intersect(
                    rays[m], ray_flags=mi.RayFlags.All, coherent=False, active=a
                )
                a &= hit.is_valid()
                last = a & (j == depth)
                pts[m] = dr.select(last, hit.p, pts[m])
                ok[m] |= last & (shape_id(hit) == target) & (keys[m] == tone.key)
                go = a & (j < depth)
                keys[m] = dr.select(go, combine(keys[m], shape_id(hit)), keys[m])
                # the query's branch at depth j: transmit (refract with the material's eta)
                # or reflect
                bit = dr.select(j < MAX_BITS, (tone.bits >> dr.minimum(j, MAX_BITS - 1)) & 1, 0)
                refract = go & (bit == 1)
                d = rays[m].d
                ng = mi.Vector3f(hit.n)
                cos = dr.dot(d, ng)
                reflected = d - 2.0 * cos * ng
                bs, _ = hit.bsdf().sample(ctx, hit, mi.Float(0.5), mi.Point2f(0.5, 0.5), refract)
                nf = dr.select(cos < 0, ng, -ng)          # facing the incoming ray
                ci = dr.abs(cos)
                r = dr.rcp(dr.select(bs.pdf > 0, bs.eta, 1.0))   # n1 / n2
                k = 1.0 - r * r * (1.0 - ci * ci)
                refracted = r * d + (r * ci - dr.sqrt(dr.maximum(k, 0.0))) * nf
                refract_ok = refract & (bs.pdf > 0) & (k > 0)
                go &= ~refract | refract_ok
                dnew = dr.normalize(dr.select(refract, refracted, reflected))
                rays[m] = dr.select(go, hit.spawn_ray(dnew), rays[m])
                alive[m] = go
            return j + 1, alive, rays, keys, pts, ok

        _, _, _, _, pts, ok = dr.while_loop(state, cond, body, label="styletrace tone anchors")
        return pts, coords, ok
