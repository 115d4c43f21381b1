"""LLaT's conditional lifting of feature lines ("Lifting Lines and Tone", West, Mukherjee and Yue,
ACM TOG 2026, Section 4, S1.4): the transport of a base path's conditioning to auxiliary paths,
the slope metric, the composition of line types, and `Lifted`, used by `line_mode lifted`.

    h2 = c n2 + s u2                (Eqs. 13-18: the half-vector's tilt c = h.n and azimuth kept)
    d = v - 2 (v.h) h               (Eq. 19, reflection; Eq. 20 refracts)
    a pair fires where |f(v) - f(u)| / |s_v - s_u| >= t                  (Eq. 23)
    sum_i prod_{j<i} w_j (1 - w_i) c_i + prod_i w_i L                    (Eq. 32, sampled by Eq. 34)

At a diffuse vertex the base direction turns by the minimal rotation taking n to n2 (S1.4).
Design: docs/design/lifted_lines.md.
"""
from __future__ import annotations

from styletrace.config.line_types import LineType
from styletrace.errors import SceneError
from styletrace.gate import dr, mi
from styletrace.kernel.lines import object_shapes, on_shapes


def tangent_chart(n: mi.Vector3f, v: mi.Vector3f):
    """(t1, t2): t1 = normalize(n x v), t2 = t1 x n (Eq. 17); where v is parallel to n any
    tangent frame.

    Args:
        n: the unit normal (mi.Vector3f). v: the incoming direction (mi.Vector3f).

    Returns:
        (t1, t2), mi.Vector3f each.
    """
    t1 = dr.cross(n, v)
    len2 = dr.squared_norm(t1)
    fallback, _ = mi.coordinate_system(n)
    t1 = dr.select(len2 > 1e-12, t1 * dr.rsqrt(dr.maximum(len2, 1e-30)), fallback)
    return t1, dr.cross(t1, n)


def transport_half_vector(h: mi.Vector3f, n: mi.Vector3f, v: mi.Vector3f, n2: mi.Vector3f,
                          v2: mi.Vector3f) -> mi.Vector3f:
    """The half-vector at the auxiliary vertex that keeps h's tilt c = h . n and its azimuth alpha
    in the chart of the incoming direction (Eqs. 13-18).

    Args:
        h, n, v: the base vertex's unit half-vector, shading normal and incoming direction.
        n2, v2: the auxiliary vertex's shading normal and incoming direction.

    Returns:
        h2 (mi.Vector3f, unit).
    """
    c = dr.clip(dr.dot(h, n), -1.0, 1.0)
    s = dr.sqrt(dr.maximum(1.0 - c * c, 0.0))
    t1, t2 = tangent_chart(n, v)
    u = h - c * n
    a1, a2 = dr.dot(u, t1), dr.dot(u, t2)
    flat = (a1 * a1 + a2 * a2) < 1e-24            # h = n: no azimuth, any will do
    a1 = dr.select(flat, 1.0, a1)
    a2 = dr.select(flat, 0.0, a2)
    t1b, t2b = tangent_chart(n2, v2)
    u2 = dr.normalize(a1 * t1b + a2 * t2b)
    # u2 is perpendicular to n2 up to rounding; remove what rounding left so that h2 . n2 = c to
    # float precision
    u2 = dr.normalize(u2 - dr.dot(u2, n2) * n2)
    return c * n2 + s * u2


def reflect(v: mi.Vector3f, h: mi.Vector3f) -> mi.Vector3f:
    """Eq. 19: the incoming direction v (towards the surface) reflected about h.

    Args:
        v: the incoming direction. h: the unit half-vector (mi.Vector3f each).

    Returns:
        mi.Vector3f.
    """
    return v - 2.0 * dr.dot(v, h) * h


def refract(v: mi.Vector3f, h: mi.Vector3f, eta: mi.Float):
    """Eq. 20: v refracted about h, h turned to face v (v . h < 0).

    Args:
        v: the incoming direction. h: the unit half-vector (mi.Vector3f each).
        eta: eta_i / eta_t (mi.Float).

    Returns:
        (direction mi.Vector3f, valid mi.Bool: no total internal reflection).
    """
    h = dr.select(dr.dot(v, h) > 0, -h, h)
    vh = dr.dot(v, h)
    k = 1.0 - eta * eta * (1.0 - vh * vh)
    d = eta * v - (eta * vh + dr.sqrt(dr.maximum(k, 0.0))) * h
    return dr.normalize(d), k > 0


def minimal_rotation(n: mi.Vector3f, n2: mi.Vector3f, w: mi.Vector3f) -> mi.Vector3f:
    """w turned by the smallest rotation taking unit n to unit n2 (Rodrigues; the diffuse rule
    of S1.4); w unchanged where n2 = -n.

    Args:
        n, n2: unit normals (mi.Vector3f). w: the direction to turn.

    Returns:
        mi.Vector3f.
    """
    axis = dr.cross(n, n2)
    c = dr.dot(n, n2)
    # R w = c w + axis x w + axis (axis . w) / (1 + c); exact for unit n, n2 (n2 = -n has no minimal
    # rotation: the lane keeps w)
    k = dr.rcp(dr.maximum(1.0 + c, 1e-12))
    out = c * w + dr.cross(axis, w) + axis * (dr.dot(axis, w) * k)
    return dr.select(c > -1.0 + 1e-6, out, w)


def slope(f_u, f_v, s_u: mi.Point2f, s_v: mi.Point2f) -> mi.Float:
    """|f(v) - f(u)| / |s_v - s_u|, per pixel; f scalar or a vector (its difference's norm).

    Args:
        f_u, f_v: the measurement at the two hits (mi.Float or mi.Vector3f).
        s_u, s_v: their image coordinates (mi.Point2f, pixels).

    Returns:
        mi.Float.
    """
    df = f_v - f_u
    num = dr.norm(df) if dr.size_v(df) == 3 else dr.abs(df)
    return num / dr.maximum(dr.norm(s_v - s_u), 1e-12)


def fires(f_u, f_v, s_u: mi.Point2f, s_v: mi.Point2f, threshold: float) -> mi.Bool:
    """1 - m(u, v) of Eq. 23: the pair's slope reaches the type's threshold.

    Args:
        f_u, f_v, s_u, s_v: as `slope`'s. threshold: t, in units of f per pixel.

    Returns:
        mi.Bool.
    """
    return slope(f_u, f_v, s_u, s_v) >= threshold


def compose_expected(w, colors, L):
    """Eq. 32: sum_i prod_{j<i} w_j (1 - w_i) c_i + prod_i w_i L.

    Args:
        w: per type in priority order, the probability that it draws no line.
        colors: per type its colour. L: the radiance where no type draws.

    Returns:
        The expected colour (numpy or Dr.Jit, as the inputs).
    """
    out = 0.0
    keep = 1.0
    for wi, ci in zip(w, colors):
        out = out + keep * (1.0 - wi) * ci
        keep = keep * wi
    return out + keep * L


def compose_sample(fired, colors, L):
    """Eq. 34 with binary metrics: the colour of the first type (in priority order) whose sample
    fired, L where none did.

    Args:
        fired: one boolean array per type (numpy or Dr.Jit). colors: per type its colour.
        L: the value where none fired.

    Returns:
        The colour per sample (numpy or Dr.Jit, as `fired`).
    """
    import numpy as np
    out = L
    for f, c in reversed(list(zip(fired, colors))):
        out = np.where(f, c, out) if isinstance(f, np.ndarray) else dr.select(f, c, out)
    return out


# ---- auxiliary paths and a line renderer over them -----------------------------------------------

class Lifted:
    """Feature lines by conditional lifting in one scene (first sensor), for a dictionary of
    `LineType`s: per camera sample a base path, and per type `count` pairs of stencil points whose
    auxiliary paths keep its conditioning; a type fires where any pair does.

    Args:
        scene: the scene. types: its `LineType`s (ordered here by priority).
        depth: the vertices tested per path (`line_depth`).
        through_diffuse: carry the paths past diffuse vertices (minimal rotation); else stop there.
        objects: the shape ids that draw lines (`line_objects`; empty: all).

    Raises:
        SceneError: the sensor's lens model is not known here, or an id names no shape.
    """

    def __init__(
        self, scene: mi.Scene, types, depth: int = 2, through_diffuse: bool = False, objects=()
    ):
        from styletrace.kernel.anchors import Tone
        self.scene = scene
        self.tone = Tone(scene)          # film conversion and projection of the first sensor
        self.types = sorted(types, key=lambda t: t.priority)
        self.depth = depth
        self.through_diffuse = through_diffuse
        # line_objects: a pair draws where a hit is on one of them
        self.shapes = object_shapes(scene, objects)

        sensor = self.tone.sensor
        # (camera to world, world to camera, aperture radius, focus distance) of a thin lens
        self.lens = None
        if self.tone.lens:
            params = mi.traverse(sensor)
            if "aperture_radius" not in params:
                raise SceneError(
                    f"lifted lines: sensor {sensor.class_name()} has an aperture whose lens model "
                    "is not known here (supported: perspective, orthographic, thinlens)"
                )
            m = sensor.world_transform()
            self.lens = (m, m.inverse(), float(dr.ravel(params["aperture_radius"])[0]),
                         float(dr.ravel(sensor.focus_distance())[0]))

    def conditioning(self, ray: mi.Ray3f) -> tuple[mi.Point2f, mi.Point2f]:
        """(s, aperture sample) of a camera ray: its film point (screen pixels, `Projection.pixels`)
        and the lens sample it left the lens with ((0.5, 0.5) without an aperture), so that `_ray(s,
        aperture)` gives the ray back.

        Args:
            ray: the camera rays (mi.Ray3f).

        Returns:
            (mi.Point2f, mi.Point2f).
        """
        o, d = mi.Point3f(ray.o), mi.Vector3f(ray.d)
        if self.lens is None:
            x, y = self.tone.projection.pixels(o + d)
            return mi.Point2f(x, y), mi.Point2f(0.5, 0.5)
        to_world, to_local, radius, focus = self.lens
        ol, dl = to_local @ o, to_local @ d
        # Mitsuba's thin lens: the ray leaves the lens point (radius * disk(aperture), 0) towards
        # the point of the focal plane z = focus that the lens centre sees at the sample's film
        # position; its origin is then moved along it to the near clip plane, which is undone here
        inv_z = dr.rcp(dr.maximum(dl.z, 1e-12))
        f = ol + dl * ((focus - ol.z) * inv_z)
        ol = ol - dl * (ol.z * inv_z)
        x, y = self.tone.projection.pixels(to_world @ mi.Point3f(f))
        disk = mi.Point2f(ol.x, ol.y) / max(radius, 1e-30)
        return mi.Point2f(x, y), mi.warp.uniform_disk_to_square_concentric(disk)

    def _ray(self, s: mi.Point2f, active, aperture=None):
        aperture = mi.Point2f(0.5, 0.5) if aperture is None else aperture
        ray, _ = self.tone.sensor.sample_ray(
            mi.Float(0.0), mi.Float(0.5), self.tone.film_uv(s.x, s.y), aperture, active
        )
        return mi.Ray3f(ray)

    @staticmethod
    def _measure(kind: str, si, travelled):
        if kind == "depth":
            return travelled
        if kind == "normal":
            return mi.Vector3f(si.n)
        if kind == "shape_id":
            return mi.Float(dr.reinterpret_array(mi.UInt32, si.shape))
        return mi.Float(dr.reinterpret_array(mi.UInt32, si.bsdf()))

    def _offsets(self, t: LineType, sampler):
        """A stencil point in the type's disk or square of radius t.radius pixels."""
        u = sampler.next_2d()
        if t.stencil == "square":
            return mi.Point2f((2.0 * u.x - 1.0) * t.radius, (2.0 * u.y - 1.0) * t.radius)
        d = mi.warp.square_to_uniform_disk_concentric(u)
        return mi.Point2f(d.x * t.radius, d.y * t.radius)

    def fired(self, s: mi.Point2f, sampler, active, aperture=None) -> list:
        """Per type (priority order): whether any of its pairs fired, for camera samples at s.

        Args:
            s: the film points (mi.Point2f, screen pixels from the centre, `Projection.pixels`).
            sampler: the lanes' random stream. active: the camera lanes (mi.Bool).
            aperture: the lens samples the rays leave with (mi.Point2f); None: the lens centre.

        Returns:
            list[mi.Bool], one per type.
        """
        scene = self.scene
        ctx = mi.BSDFContext()
        # the base path: xi (each vertex's sampled direction, half-vector, and the vertex's frame)
        base = []
        ray, alive = self._ray(s, active, aperture), mi.Bool(active)
        for j in range(self.depth):
            si = scene.ray_intersect(ray, active=alive)
            hit = alive & si.is_valid()
            bsdf = si.bsdf(ray)
            bs, _ = bsdf.sample(ctx, si, sampler.next_1d(), sampler.next_2d(), hit)
            d = si.to_world(bs.wo)
            diffuse = hit & ~mi.has_flag(bs.sampled_type, mi.BSDFFlags.Glossy) & \
                ~mi.has_flag(bs.sampled_type, mi.BSDFFlags.Delta)
            through = hit & mi.has_flag(bs.sampled_type, mi.BSDFFlags.Transmission)
            n = mi.Vector3f(si.sh_frame.n)
            # the (generalised) half-vector: reflection d - v; refraction v - eta d (eta = eta_t
            # / eta_i)
            eta = dr.select(through, bs.eta, 1.0)
            h = dr.normalize(dr.select(through, ray.d - eta * d, d - ray.d))
            go = hit & (bs.pdf > 0) & (~diffuse if not self.through_diffuse else True)
            base.append(
                dict(
                    alive=alive,
                    n=n,
                    v=mi.Vector3f(ray.d),
                    h=h,
                    d=d,
                    diffuse=diffuse,
                    through=through,
                    eta=eta,
                    go=go,
                )
            )
            ray = si.spawn_ray(d)
            alive = go
        out = []
        for t in self.types:
            any_fire = mi.Bool(False)
            for _ in range(t.count):
                du, dv = self._offsets(t, sampler), self._offsets(t, sampler)
                paths = [self._ray(s + du, active, aperture), self._ray(s + dv, active, aperture)]
                travelled = [mi.Float(0.0), mi.Float(0.0)]
                live = mi.Bool(active)
                for j in range(self.depth):
                    b = base[j]
                    live &= b["alive"]
                    sis = [scene.ray_intersect(r, active=live) for r in paths]
                    hits = [live & x.is_valid() for x in sis]
                    fire = hits[0] ^ hits[1]
                    both = hits[0] & hits[1]
                    for k in range(2):
                        travelled[k] = travelled[k] + dr.select(hits[k], sis[k].t, 0.0)
                    if t.measurement in ("shape_id", "material_id"):
                        fa, fb = (
                            self._measure(t.measurement, sis[0], None),
                            self._measure(t.measurement, sis[1], None),
                        )
                        fire |= both & (fa != fb)
                    else:
                        fa = self._measure(t.measurement, sis[0], travelled[0])
                        fb = self._measure(t.measurement, sis[1], travelled[1])
                        fire |= both & (slope(fa, fb, du, dv) >= t.threshold)
                    if self.shapes:
                        fire &= on_shapes(sis[0], self.shapes) | on_shapes(sis[1], self.shapes)
                    any_fire |= fire
                    # carry on past this vertex with xi kept (cut where the pair's objects part:
                    # their lines are already drawn, or where the base path ends)
                    same = both & (dr.reinterpret_array(mi.UInt32, sis[0].shape) ==
                                   dr.reinterpret_array(mi.UInt32, sis[1].shape))
                    live = same & b["go"] & ~fire
                    if j + 1 < self.depth:
                        new = []
                        for k in range(2):
                            n2, v2 = mi.Vector3f(sis[k].sh_frame.n), mi.Vector3f(paths[k].d)
                            h2 = transport_half_vector(b["h"], b["n"], b["v"], n2, v2)
                            refracted, ok = refract(v2, h2, dr.rcp(b["eta"]))
                            live &= ~b["through"] | ok
                            d2 = dr.select(b["diffuse"], minimal_rotation(b["n"], n2, b["d"]),
                                           dr.select(b["through"], refracted, reflect(v2, h2)))
                            new.append(sis[k].spawn_ray(dr.normalize(d2)))
                        paths = new
            out.append(any_fire)
        return out

    def render(self, spp: int, seed: int = 0, background=(1.0, 1.0, 1.0), jitter: bool = True):
        """Eq. 34's estimator over the whole image, with `background` for L (tests, figures); the
        per-sample results are kept in `samples`.

        Args:
            spp: camera samples per pixel. seed: the independent sampler's seed.
            background: the colour where no type fires (RGB).
            jitter: jitter the samples within their pixel; False: every one at the pixel centre.

        Returns:
            (image [h, w, 3], per type the fraction of samples it fired [h, w]), numpy arrays.
        """
        import numpy as np
        w, h = int(self.tone.width), int(self.tone.height)
        n = w * h * spp
        idx = np.arange(n) // spp
        col, row = (idx % w).astype(np.float32), (idx // w).astype(np.float32)
        sampler = mi.load_dict({"type": "independent"})
        sampler.seed(seed, n)
        jx, jy = np.array(sampler.next_2d()) if jitter else np.full((2, n), 0.5, np.float32)
        # the Projection convention: x grows to the left
        s = mi.Point2f(w / 2 - col - jx, h / 2 - row - jy)
        fired = self.fired(s, sampler, mi.Bool(True))
        L = np.array(background, np.float32)
        colors = [np.array(t.color, np.float32) for t in self.types]
        f = [np.array(x, bool) for x in fired]
        # per sample, for inspection and tests
        self.samples = [x.reshape(h, w, spp) for x in f]
        img = compose_sample([x[:, None] for x in f], colors, L[None])
        img = img.reshape(h, w, spp, 3).mean(axis=2)
        return img, [x.reshape(h, w, spp).mean(axis=2) for x in f]
