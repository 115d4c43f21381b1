"""Building blocks of LLaT's conditional lifting for feature lines (not yet wired into the
integrator).

Reference: "Lifting Lines and Tone: Image-space Stylization in Path-space", Rex West, Sayan
Mukherjee and Yonghao Yue (ACM TOG 45(4), 2026), Section 4 (Eqs. 13-20, 23, 31-34) and
supplement S1.4.

An auxiliary path keeps the base path's conditioning xi (the lens sample, each half-vector's tilt,
each reflect/refract choice) while its image coordinate moves. At a glossy or specular vertex the
base path's half-vector h (unit, in the hemisphere of the shading normal n) is carried to the
auxiliary vertex, whose normal is n2 and incoming direction v2:
    c = h . n,  s = sqrt(1 - c^2),  u = (h - c n) / s                   (Eq. 14: tilt and azimuth)
    t1 = normalize(n x v),  t2 = t1 x n,  alpha = atan2(u . t2, u . t1) (Eqs. 17-18: chart of v)
    u2 = cos(alpha) t1' + sin(alpha) t2',  t1' = normalize(n2 x v2), t2' = t1' x n2
    h2 = c n2 + s u2                                                     (Eq. 16: tilt kept)
then the auxiliary direction leaves by reflection d = v - 2 (v . h) h (Eq. 19) or refraction
d = eta v - (eta (v . h) + sqrt(1 - eta^2 (1 - (v . h)^2))) h with h facing v (Eq. 20). At a diffuse
vertex the base direction is turned by the minimal rotation taking n to n2 (supplement S1.4).

Lines are detected by the slope metric m(u, v) = [|f(v) - f(u)| / |s_v - s_u| < t] (Eq. 23), in
pixels, per line type (its measurement f, threshold t). Types compose in priority order (Eqs.
31-34): with w_i the probability that type i draws no line, the expected result is
    sum_i prod_{j<i} w_j (1 - w_i) c_i + prod_i w_i L                      (Eq. 32)
and its binary-metric estimator returns the colour of the first type that fires, L where none does
(Eq. 34).

What is here: the transport, the two scattering rules, minimal rotation, the slope metric, the
composition (functions on Dr.Jit arrays, and `compose_expected` / `compose_sample` on numpy or
Dr.Jit), and `Lifted`, which traces the auxiliary paths of a line dictionary for camera samples. The
integrator uses it with `line_mode lifted` (`line_types`, config/line_types.py): per camera sample
the types are tested first and L is traced only where none fired (Eq. 34). West 2021's cone
(kernel/lines.py) stays the `absorb` mode.
"""
from __future__ import annotations

from styletrace.config.line_types import LineType
from styletrace.errors import SceneError
from styletrace.gate import dr, mi
from styletrace.kernel.lines import object_shapes, on_shapes


def tangent_chart(n: mi.Vector3f, v: mi.Vector3f):
    """(t1, t2): t1 = normalize(n x v), t2 = t1 x n (Eq. 17); where v is parallel to n any
    tangent frame."""
    t1 = dr.cross(n, v)
    len2 = dr.squared_norm(t1)
    fallback, _ = mi.coordinate_system(n)
    t1 = dr.select(len2 > 1e-12, t1 * dr.rsqrt(dr.maximum(len2, 1e-30)), fallback)
    return t1, dr.cross(t1, n)


def transport_half_vector(h: mi.Vector3f, n: mi.Vector3f, v: mi.Vector3f, n2: mi.Vector3f,
                          v2: mi.Vector3f) -> mi.Vector3f:
    """The half-vector at the auxiliary vertex (normal n2, incoming v2) that keeps h's tilt c = h .
    n and its azimuth alpha in the chart of the incoming direction (Eqs. 13-18)."""
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
    """Eq. 19: the incoming direction v (towards the surface) reflected about h."""
    return v - 2.0 * dr.dot(v, h) * h


def refract(v: mi.Vector3f, h: mi.Vector3f, eta: mi.Float):
    """Eq. 20 with eta = eta_i / eta_t and h turned to face v (v . h < 0); (direction, valid: no
    total internal reflection)."""
    h = dr.select(dr.dot(v, h) > 0, -h, h)
    vh = dr.dot(v, h)
    k = 1.0 - eta * eta * (1.0 - vh * vh)
    d = eta * v - (eta * vh + dr.sqrt(dr.maximum(k, 0.0))) * h
    return dr.normalize(d), k > 0


def minimal_rotation(n: mi.Vector3f, n2: mi.Vector3f, w: mi.Vector3f) -> mi.Vector3f:
    """w turned by the smallest rotation taking unit n to unit n2 (Rodrigues; the diffuse rule
    of S1.4)."""
    axis = dr.cross(n, n2)
    c = dr.dot(n, n2)
    # R w = c w + axis x w + axis (axis . w) / (1 + c); exact for unit n, n2 (n2 = -n has no minimal
    # rotation: the lane keeps w)
    k = dr.rcp(dr.maximum(1.0 + c, 1e-12))
    out = c * w + dr.cross(axis, w) + axis * (dr.dot(axis, w) * k)
    return dr.select(c > -1.0 + 1e-6, out, w)


def slope(f_u, f_v, s_u: mi.Point2f, s_v: mi.Point2f) -> mi.Float:
    """|f(v) - f(u)| / |s_v - s_u| (pixels); f scalar or a vector (its difference's norm)."""
    df = f_v - f_u
    num = dr.norm(df) if dr.size_v(df) == 3 else dr.abs(df)
    return num / dr.maximum(dr.norm(s_v - s_u), 1e-12)


def fires(f_u, f_v, s_u: mi.Point2f, s_v: mi.Point2f, threshold: float) -> mi.Bool:
    """1 - m(u, v) of Eq. 23: the pair's slope reaches the type's threshold."""
    return slope(f_u, f_v, s_u, s_v) >= threshold


def compose_expected(w, colors, L):
    """Eq. 32: sum_i prod_{j<i} w_j (1 - w_i) c_i + prod_i w_i L; `w` and `colors` in
    priority order."""
    out = 0.0
    keep = 1.0
    for wi, ci in zip(w, colors):
        out = out + keep * (1.0 - wi) * ci
        keep = keep * wi
    return out + keep * L


def compose_sample(fired, colors, L):
    """Eq. 34 with binary metrics: the colour of the first type (in priority order) whose sample
    fired, L where none did. `fired`: one boolean array per type (numpy or Dr.Jit)."""
    import numpy as np
    out = L
    for f, c in reversed(list(zip(fired, colors))):
        out = np.where(f, c, out) if isinstance(f, np.ndarray) else dr.select(f, c, out)
    return out


# ---- auxiliary paths and a line renderer over them -----------------------------------------------

class Lifted:
    """Feature lines by conditional lifting in one scene (first sensor), for a dictionary of
    `LineType`s.

    Per camera sample at image coordinate s (pixels right and up of the centre, as
    styles.base.Projection) the base path is traced from the lens point `aperture` (the lens centre
    where none is given) through s, sampling each non-diffuse vertex's BSDF (that choice and its
    half-vector are the conditioning xi). For each type, `count` pairs of stencil points (u, v)
    around s give two auxiliary paths each, traced vertex by vertex with xi kept: at a glossy or
    specular base vertex the auxiliary reflects about the base's half-vector transported to it
    (`transport_half_vector`), at a diffuse one it turns the base's direction by `minimal_rotation`
    (only with `through_diffuse`; otherwise the paths stop there, as West 2021's lines do). At every
    depth up to `depth` the pair fires when exactly one of its paths hits, when the two hit
    different shapes and the type measures shape or material ids, or when the slope |f(v) - f(u)| /
    |v - u| reaches the type's threshold; with `objects` (shape ids, `line_objects`) only where one
    of the pair's hits there is on one of those shapes. A type fires if any of its pairs fires; the
    first type in priority order that fires gives the sample's colour (Eq. 34), `background` where
    none. At a transmitting base vertex the auxiliary refracts (Eq. 20) about the transported
    generalised half-vector h = normalize(v - eta d) (eta: the base's sampled relative index),
    keeping the base's reflect-or-refract choice; where it cannot (total internal reflection) its
    pair stops.

    A camera ray is turned into its film coordinate and lens sample by `conditioning` (pinhole: the
    pixel it passes through; thin lens: the lens point it leaves from and the film point of its
    focus), so the base and auxiliary paths of a depth-of-field render leave from the sample's own
    lens point."""

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
        """(s, aperture sample) of a camera ray: its film point (pixels right and up of the centre)
        and the lens sample it left the lens with ((0.5, 0.5) without an aperture), so that `_ray(s,
        aperture)` gives the ray back."""
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
        """Per type (priority order): whether any of its pairs fired, for camera samples at s
        (leaving the lens at `aperture`, a lens sample; None: the lens centre)."""
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
        """(image [h, w, 3] of Eq. 34's estimator over `spp` samples per pixel, per type the
        fraction of samples it fired [h, w]). jitter=False puts every sample at the pixel centre."""
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
