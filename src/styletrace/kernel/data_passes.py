"""Data passes: Depth, Normal, Vector, Position, UV, Mist, Object and Material Index, Denoising
Albedo and Emission of the first surface each camera sample sees, per pixel, in Blender's
conventions (the compositor's Vector Blur, Z Combine, ID Mask and Mist read them unchanged).

    names = parse_passes("depth,vector")              # ('depth', 'vector'); bad names refused
    view = View.of(scene.sensors()[0])                # a camera's world -> pixel map
    motion = Motion(previous=to_world_before, next=to_world_after)  # the camera one frame away
    out = render_data_passes(scene, names, spp=4, seed=0, motion=motion)
    out["depth"], out["normal"], out["vector"]       # H x W, H x W x 3, H x W x 4 float32

The passes trace primary rays of their own (a camera ray per camera sample, jittered in its pixel,
and one intersection): the render's image is not touched, so it is the same bit for bit with or
without them. Each pass is filtered over the pixel's samples as Cycles filters it (measured with
Cycles 5.0, tests/blender/test_data_passes.py):

- depth: the distance along the camera's view axis to the hit, of the pixel's first sample only
  (Cycles writes depth at sample 0); `BACKGROUND_DEPTH` where that sample hits nothing;
- normal: the world-space shading normal, turned towards the camera, averaged over all samples
  (a sample that hits nothing counts as 0, so an edge pixel's normal is shorter);
- vector: (x_prev - x, y_prev - y, x - x_next, y - y_next) in pixels, x to the right and y up, of
  the hit point as the previous and the next frame's camera see it, where it sits in that frame
  (`Motion`); averaged over the samples that hit a surface; 0 where none does, and 0 everywhere
  without motion;
- position: the world-space hit point of the pixel's first sample (0 where it hits nothing);
- uv: (u, v, a): the hit's texture coordinates in Blender's orientation (u, 1 - v of Mitsuba's
  `si.uv`: Blender's v runs up the image), averaged over all samples (a miss as 0), and a, the
  share of samples that hit a surface;
- mist: `kernel.mist`'s amount at the hit, averaged over all samples, a miss as 1;
- object_index, material_index: the pass indices of the shape the first sample hits
  (`kernel.pass_indices`, carried in its id), 0 where it hits nothing or carries none;
- albedo: the denoiser's albedo guide (`kernel.guides.first_hit`, a pixel's box mean of rays of
  its own, with this seed);
- emission: the radiance the hit's own emitter sends to the camera (an area light's surface, an
  emitting mesh), averaged over all samples, a miss as 0 (the world is not in it);
- crypto_object, crypto_material: the Cryptomatte standard's ranks of the hit shapes' object and
  material ids (`kernel.asset_names`, `kernel.crypto_ranks`): per pixel, the `LEVELS` ids that
  cover most of its samples, each with its share (a miss covers none), as 3 RGBA layers
  (id, coverage, id, coverage); the result's `MANIFEST` entry names them
  ({'CryptoObject' | 'CryptoMaterial': {name: 8 hex digits}}).
Docs: docs/passes.md.
"""
from __future__ import annotations

import contextlib
from dataclasses import dataclass
from typing import Any, Iterable

import numpy as np

from styletrace.errors import SceneError, UsageError
from styletrace.gate import dr, mi
from styletrace.host_arrays import aligned
from styletrace.kernel.asset_names import MATERIAL, OBJECT, NameTable
from styletrace.kernel.crypto_ranks import LEVELS, ranks
from styletrace.kernel.mist import parse_mist
from styletrace.kernel.pass_indices import IndexTable

#: the data passes, in the order they are written
DATA_PASSES = ("depth", "normal", "vector", "position", "uv", "mist", "object_index",
               "material_index", "albedo", "emission", "crypto_object", "crypto_material")
#: channels of each pass (a Cryptomatte pass: `LEVELS` (id, coverage) pairs)
CHANNELS = {"depth": 1, "normal": 3, "vector": 4, "position": 3, "uv": 3, "mist": 1,
            "object_index": 1, "material_index": 1, "albedo": 3, "emission": 3,
            "crypto_object": 2 * LEVELS, "crypto_material": 2 * LEVELS}
#: the Cryptomatte types of the Cryptomatte passes, as Cycles names them
CRYPTO = {"crypto_object": OBJECT, "crypto_material": MATERIAL}
#: the result's entry of the Cryptomatte passes' manifests (present only where one is asked for)
MANIFEST = "manifest"
#: Depth where the first sample hits nothing: Cycles' value (1e10)
BACKGROUND_DEPTH = 1e10
#: camera samples traced at once (bounds the memory of a launch and of its numpy copies)
LANES = 1 << 20
#: how far a camera's fitted pixel map may be off a pinhole or orthographic one, in film widths
FIT_TOLERANCE = 1e-4


def parse_passes(value: Any, name: str = "passes") -> tuple[str, ...]:
    """The data passes asked for, in `DATA_PASSES` order, each once.

    Args:
        value: None or '' (none), a comma-separated string ('depth,vector') or an iterable of names.
        name: how the caller names the setting, for the error ('--passes', 'passes').

    Returns:
        The names, a tuple (empty for none).

    Raises:
        UsageError: a name that is no data pass (one line naming it and the allowed ones).
    """
    if value is None:
        return ()
    items = value.split(",") if isinstance(value, str) else list(value)
    asked = []
    for item in items:
        if not isinstance(item, str):
            raise UsageError(f"bad value {item!r} for {name}: expected a comma-separated list of "
                             f"{', '.join(DATA_PASSES)}")
        key = item.strip().lower()
        if not key and isinstance(value, str) and not value.strip():
            continue  # '' asks for none
        if key not in DATA_PASSES:
            raise UsageError(f"bad value {item.strip()!r} for {name}: expected a comma-separated "
                             f"list of {', '.join(DATA_PASSES)}")
        asked.append(key)
    return tuple(p for p in DATA_PASSES if p in asked)


def to_world_of(sensor) -> np.ndarray:
    """A sensor's to_world.

    Args:
        sensor: the mi.Sensor.

    Returns:
        The 4x4 float64 matrix.
    """
    return np.array(sensor.world_transform().matrix, dtype=np.float64).reshape(4, 4, -1)[..., 0]


@dataclass(frozen=True)
class View:
    """A camera's map from world space to the film's pixels: the sensor's to_world, whether it is
    orthographic, and the affine map from its local coordinates (x/z, y/z; orthographic: x, y) to
    film fractions (`of` fits it to the sensor's own rays).

    Args:
        to_world: the sensor's to_world (4x4, float64).
        ortho: orthographic (rays parallel to the local z axis).
        film: 2 x 3: (u, v) = film @ (q_x, q_y, 1), u to the right and v down, in [0, 1] on the
            film's crop window.
        size: the crop window's (width, height) in pixels.
    """
    to_world: np.ndarray
    ortho: bool
    film: np.ndarray
    size: tuple[int, int]

    @classmethod
    def of(cls, sensor) -> "View":
        """The view of a pinhole, thin lens or orthographic sensor, fitted to the rays it samples
        through the film's corners and centre (the lens's centre for a thin lens).

        Args:
            sensor: the mi.Sensor (its film's crop window is the image).

        Returns:
            The View.

        Raises:
            SceneError: a sensor whose rays are not a pinhole's or parallel (a spherical camera,
                a radiance meter), which no pixel map projects.
        """
        to_world = to_world_of(sensor)
        size = tuple(int(v) for v in sensor.film().crop_size())
        corners = np.array([[0, 0], [1, 0], [0, 1], [1, 1], [0.5, 0.5], [0.25, 0.75]])
        # aligned: one kernel code whatever numpy's allocator gives (host_arrays)
        at = mi.Point2f(aligned(corners[:, 0]), aligned(corners[:, 1]))
        ray, _ = sensor.sample_ray(mi.Float(sensor.shutter_open()), mi.Float(0.5), at,
                                   mi.Point2f(0.5, 0.5))
        shape = (len(corners), 3)  # (one ray only where the sensor ignores the film position)
        o = np.broadcast_to(np.array(ray.o, dtype=np.float64).reshape(3, -1).T, shape)
        d = np.broadcast_to(np.array(ray.d, dtype=np.float64).reshape(3, -1).T, shape)
        inverse = np.linalg.inv(to_world)
        local_o = o @ inverse[:3, :3].T + inverse[:3, 3]
        local_d = d @ inverse[:3, :3].T
        unit = local_d / np.linalg.norm(local_d, axis=1, keepdims=True)
        ortho = bool(np.abs(unit - unit[0]).max() < 1e-6)
        if ortho:
            q = local_o[:, :2]
        else:
            if (local_d[:, 2] <= 0).any():
                raise SceneError(f"the vector pass needs a pinhole, thin lens or orthographic "
                                 f"camera; {type(sensor).__name__} looks behind itself")
            q = local_d[:, :2] / local_d[:, 2:3]
        rows = np.concatenate([q, np.ones((len(q), 1))], axis=1)
        film, *_ = np.linalg.lstsq(rows, corners, rcond=None)
        if np.abs(rows @ film - corners).max() > FIT_TOLERANCE:
            raise SceneError(f"the vector pass needs a pinhole, thin lens or orthographic camera, "
                             f"not {type(sensor).__name__}")
        return cls(to_world, ortho, film.T, size)

    def moved(self, to_world) -> "View":
        """This camera placed elsewhere: the same lens and film, another to_world.

        Args:
            to_world: the sensor's to_world there (4x4).

        Returns:
            The View.
        """
        return View(np.asarray(to_world, dtype=np.float64), self.ortho, self.film, self.size)

    def project(self, p):
        """Where world points land on the film, traced in Dr.Jit (the camera's numbers as opaque
        values: a new camera reuses the compiled kernel).

        Args:
            p: world positions (mi.Point3f).

        Returns:
            (film positions in pixels, x to the right and y down (mi.Point2f); mi.Bool: the point
            is in front of the camera, where a pinhole's position means something).
        """
        inverse = np.linalg.inv(self.to_world[:3, :3])
        rel = p - _opaque_point(self.to_world[:3, 3])
        # relative to the camera first: large world coordinates keep their float32 precision
        x, y, z = (_dot(inverse[i], rel) for i in range(3))
        if self.ortho:
            qx, qy, front = x, y, mi.Bool(True)
        else:
            front = z > 0
            z = dr.select(front, z, 1.0)
            qx, qy = x / z, y / z
        f = [[dr.opaque(mi.Float, float(v)) for v in row] for row in self.film]
        w, h = self.size
        return mi.Point2f((f[0][0] * qx + f[0][1] * qy + f[0][2]) * w,
                          (f[1][0] * qx + f[1][1] * qy + f[1][2]) * h), front

    def pixels(self, points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """`project` of points given on the host.

        Args:
            points: N x 3 world positions.

        Returns:
            (N x 2 film positions in pixels, x to the right and y down; N booleans: in front).
        """
        at, front = self.project(mi.Point3f(*np.asarray(points, dtype=np.float32).T))
        dr.eval(at, front)
        return (np.array(at, dtype=np.float64).reshape(2, -1).T,
                np.broadcast_to(np.array(front, dtype=bool), (len(points),)).copy())


def _opaque_point(v) -> mi.Point3f:
    return mi.Point3f(*(dr.opaque(mi.Float, float(x)) for x in v))


def _dot(row, v):
    return (dr.opaque(mi.Float, float(row[0])) * v.x + dr.opaque(mi.Float, float(row[1])) * v.y
            + dr.opaque(mi.Float, float(row[2])) * v.z)


def _moved(m: np.ndarray, p):
    """The points p (mi.Point3f) mapped by the 4x4 matrix m (opaque: no new kernel per frame)."""
    m = np.asarray(m, dtype=np.float64)
    return mi.Point3f(*(_dot(m[i], p) + dr.opaque(mi.Float, float(m[i, 3])) for i in range(3)))


def view_depth(to_world: np.ndarray, p):
    """Distance along a camera's view axis (its local +z) from the camera's plane.

    Args:
        to_world: the sensor's to_world (4x4). p: world positions (mi.Point3f).

    Returns:
        mi.Float.
    """
    axis = to_world[:3, 2] / np.linalg.norm(to_world[:3, 2])
    return _dot(axis, p - _opaque_point(to_world[:3, 3]))


@dataclass(frozen=True)
class Motion:
    """The scene one frame before and one frame after the rendered frame.

    Args:
        previous, next: the camera in those frames: a `View`, or a 4x4 to_world for the rendered
            camera placed there (its lens and film kept).
        shapes: (shape, to previous, to next) for each shape that moves: the mi.Shape (a mesh, or
            an `instance`), and the 4x4 maps of its points from world space now to world space in
            the previous and the next frame (rigid motion: M_then @ inverse(M_now)). Shapes not
            named stay where they are.
    """
    previous: Any
    next: Any
    shapes: tuple = ()


def shape_key(shape) -> int:
    """The registry id a hit on `shape` reports (`si.instance` for an instance, else `si.shape`).

    Args:
        shape: an mi.Shape of the scene.

    Returns:
        The id, an int.
    """
    return int(dr.reinterpret_array(mi.UInt32, mi.ShapePtr(shape))[0])


def _hits(scene, sensor, first: int, count: int, spp: int, seed: int):
    """Trace the camera rays of pixels [first, first + count), spp each, and find their first hits.

    Lane i is pixel first + i // spp; its random numbers are a PCG32 stream of its own (by the
    passes' seed and the lane's index in the whole image), so the passes do not depend on how the
    image is cut into launches.

    Returns:
        (valid (mi.Bool), the hit points (mi.Point3f, the origin where none), the shading normals
        turned towards the camera (mi.Vector3f), the hit's registry id (`shape_key`'s, mi.UInt32),
        the hits themselves (mi.SurfaceInteraction3f)).
    """
    w, h = (int(v) for v in sensor.film().crop_size())
    n = count * spp
    idx = dr.arange(mi.UInt32, n)
    # opaque: every launch of every render reuses one kernel
    start = dr.opaque(mi.UInt32, first)
    rng = mi.PCG32(n)
    # `seed`, not the constructor: that adds each lane's index within the launch
    rng.seed(dr.opaque(mi.UInt64, int(seed) & 0xFFFFFFFF),
             mi.UInt64(idx) + mi.UInt64(start) * spp)
    pixel = idx // spp + start
    y = pixel // w
    x = pixel - y * w
    pos = mi.Point2f((mi.Float(x) + rng.next_float32()) / w, (mi.Float(y) + rng.next_float32()) / h)
    aperture = mi.Point2f(rng.next_float32(), rng.next_float32())
    ray, _ = sensor.sample_ray(mi.Float(sensor.shutter_open()), mi.Float(0.5), pos, aperture)
    # a sensor whose rays ignore the film position (a radiance meter) gives one ray: one per lane
    ray.o += mi.Vector3f(dr.zeros(mi.Float, n))
    si = scene.ray_intersect(ray, ray_flags=mi.RayFlags.All, coherent=True)
    valid = si.is_valid()
    # Cycles turns the normal of a surface seen from its back towards the viewer
    normal = dr.select(dr.dot(si.n, ray.d) > 0, -si.sh_frame.n, si.sh_frame.n)
    inst = dr.reinterpret_array(mi.UInt32, si.instance)
    key = dr.select(inst != 0, inst, dr.reinterpret_array(mi.UInt32, si.shape))
    # a lane that hits nothing gets the origin: no inf reaches the projections
    return valid, dr.select(valid, si.p, mi.Point3f(0.0)), normal, key, si


def _then(view: View, where: Any) -> View:
    return where if isinstance(where, View) else view.moved(where)


def _vectors(p, key, view: View, motion: Motion):
    """Each lane's Vector: 4 mi.Float (0 where a point is behind one of the cameras)."""
    before, after = mi.Point3f(p), mi.Point3f(p)
    for shape, to_previous, to_next in motion.shapes:
        mine = key == dr.opaque(mi.UInt32, shape_key(shape))
        before = dr.select(mine, _moved(to_previous, p), before)
        after = dr.select(mine, _moved(to_next, p), after)
    now, front = view.project(p)
    prev, front_prev = _then(view, motion.previous).project(before)
    nxt, front_next = _then(view, motion.next).project(after)
    ok = front & front_prev & front_next
    # film y points down, Blender's up: the y components change sign
    return [dr.select(ok, c, 0.0) for c in (prev.x - now.x, now.y - prev.y,
                                            now.x - nxt.x, nxt.y - now.y)]


@contextlib.contextmanager
def placed(sensor, to_world):
    """The sensor's to_world replaced by `to_world` while the block runs (None: left as it is).

    Args:
        sensor: the mi.Sensor. to_world: a 4x4 matrix, or None.
    """
    if to_world is None:
        yield
        return
    params = mi.traverse(sensor)
    own = to_world_of(sensor)
    params["to_world"] = mi.ScalarTransform4f(np.asarray(to_world, dtype=np.float64))
    params.update()
    try:
        yield
    finally:
        params["to_world"] = mi.ScalarTransform4f(own)
        params.update()


def render_data_passes(scene, names: Iterable[str], spp: int, seed: int = 0,
                       motion: Motion | None = None, lanes: int = LANES,
                       camera=None, mist: Any = None) -> dict[str, np.ndarray]:
    """The data passes of the scene's first sensor, over its film's crop window (module doc).

    Args:
        scene: the mi.Scene. names: the passes (`parse_passes`'s names).
        spp: camera samples per pixel (>= 1). seed: the passes' seed (their jitter).
        motion: the neighbouring frames (None: a still, whose vector is 0).
        lanes: camera samples per launch (whole pixels; at least one pixel).
        camera: the sensor's to_world (4x4) in place of the scene's while they are traced (a
            turntable's frame), or None.
        mist: the mist settings (`kernel.mist.parse_mist`'s values; None: Blender's defaults).

    Returns:
        {name: float32 array}: H x W for the passes of one channel, else H x W x `CHANNELS`
        (an empty dict for no names); with a Cryptomatte pass, also `MANIFEST`: {type name
        ('CryptoObject', 'CryptoMaterial'): its manifest} for the types asked for.

    Raises:
        SceneError: vector with a sensor no pixel map projects (`View.of`).
        UsageError: spp below 1, or bad mist settings.
    """
    names = parse_passes(tuple(names))
    if not names:
        return {}
    if int(spp) < 1:
        raise UsageError(f"bad value {spp} for the data passes' camera samples: expected >= 1")
    mist = parse_mist(mist)
    sensor = scene.sensors()[0]
    with placed(sensor, camera):
        out = _render(scene, sensor, names, int(spp), seed, motion, lanes, mist)
        if "albedo" in names:  # the denoiser's own guide, its rays its own
            from styletrace.kernel.guides import first_hit
            out["albedo"] = first_hit(scene, int(spp), seed, footprint="pixel",
                                      lanes_per_launch=lanes).albedo
    result = {name: out[name] for name in names}
    if MANIFEST in out:
        result[MANIFEST] = out[MANIFEST]
    return result


def parallel(sensor) -> bool:
    """Whether the sensor's rays are parallel (an orthographic camera), from two of its rays.

    Args:
        sensor: the mi.Sensor.

    Returns:
        True where the rays through two corners of the film have one direction.
    """
    at = mi.Point2f(aligned(np.array([0.1, 0.9])), aligned(np.array([0.1, 0.9])))
    ray, _ = sensor.sample_ray(mi.Float(sensor.shutter_open()), mi.Float(0.5), at,
                               mi.Point2f(0.5, 0.5))
    d = np.broadcast_to(np.array(ray.d, dtype=np.float64).reshape(3, -1).T, (2, 3))
    return bool(np.abs(d[0] - d[1]).max() < 1e-6)


def _distance(to_world: np.ndarray, ortho: bool, p):
    """Distance from the camera to p (mi.Point3f), as the mist measures it (`kernel.mist`)."""
    if ortho:
        return dr.abs(view_depth(to_world, p))
    return dr.norm(p - _opaque_point(to_world[:3, 3]))


def _first(values, count: int, spp: int) -> list:
    """The pixels' first samples' values (a list of mi.Float, one lane per camera sample)."""
    return [dr.gather(mi.Float, v, dr.arange(mi.UInt32, count) * spp) for v in values]


def _render(scene, sensor, names, spp, seed, motion, lanes, mist) -> dict[str, np.ndarray]:
    """`render_data_passes` on the sensor as it is placed now, but albedo: launches of whole
    pixels, each pass reduced over its pixels' samples (module doc) in the kernel, only pixels
    copied out."""
    w, h = (int(v) for v in sensor.film().crop_size())
    view = View.of(sensor) if "vector" in names else None
    to_world = to_world_of(sensor)
    ortho = parallel(sensor) if "mist" in names else False
    table = (IndexTable.of(scene) if {"object_index", "material_index"} & set(names)
             else None)
    crypto = [name for name in names if name in CRYPTO]
    named = NameTable.of(scene) if crypto else None
    out = {name: np.zeros((h * w, CHANNELS[name]), np.float32) for name in names
           if name != "albedo"}
    step = max(1, int(lanes) // spp)
    for first in range(0, w * h, step):
        count = min(step, w * h - first)
        valid, p, normal, key, si = _hits(scene, sensor, first, count, spp, seed)
        hit = mi.Float(valid)
        # every lane's values in one kernel first: a reduction or a gather of values not yet
        # evaluated would trace the rays again for each
        lane = {}
        if "depth" in out:
            lane["depth"] = [dr.select(valid, view_depth(to_world, p), BACKGROUND_DEPTH)]
        if "normal" in out:
            lane["normal"] = [hit * c for c in normal]
        if "vector" in out:
            lane["vector"] = ([hit * c for c in _vectors(p, key, view, motion)]
                              if motion is not None else [])
        if "position" in out:
            lane["position"] = list(p)
        if "uv" in out:
            # Blender's v runs up the image, Mitsuba's texture v down it (the exporter flips it)
            lane["uv"] = [hit * si.uv.x, hit * (1.0 - si.uv.y), hit]
        if "mist" in out:
            lane["mist"] = [dr.select(valid, mist.amount(_distance(to_world, ortho, p)), 1.0)]
        if table is not None:
            lane["object_index"], lane["material_index"] = ([c] for c in table.lookup(si, valid))
        if "emission" in out:
            # a lane whose shape emits nothing holds a null emitter: its call gives 0
            radiance = si.emitter(scene, valid).eval(si, valid)
            lane["emission"] = [dr.select(valid, c, 0.0) for c in radiance]
        ids = dict(zip(CRYPTO, named.lookup(si, valid))) if named is not None else {}
        dr.eval(hit, lane, ids)
        found = {}
        if "depth" in out:  # the pixel's first sample's
            found["depth"] = _first(lane["depth"], count, spp)
        for name in ("normal", "uv", "mist", "emission"):  # every sample's
            if name in out:
                found[name] = [dr.block_sum(c, spp) / spp for c in lane[name]]
        if "vector" in out:  # the samples that hit a surface
            hits = dr.block_sum(hit, spp)
            found["vector"] = [dr.select(hits > 0, dr.block_sum(c, spp) / hits, 0.0)
                               for c in lane["vector"]] or [dr.zeros(mi.Float, count)] * 4
        for name in ("position", "object_index", "material_index"):  # the first sample's
            if name in out:
                found[name] = _first(lane[name], count, spp)
        dr.eval(found)
        for name, columns in found.items():
            out[name][first:first + count] = np.stack(
                [np.array(c, dtype=np.float32) for c in columns], -1)
        for name in crypto:  # ranked on the host: a pixel's samples are a row
            out[name][first:first + count] = ranks(
                np.array(ids[name], dtype=np.uint32).reshape(count, spp))
    done = {name: arr.reshape(h, w, -1) if CHANNELS[name] > 1 else arr.reshape(h, w)
            for name, arr in out.items()}
    if crypto:
        done[MANIFEST] = {CRYPTO[name]: named.manifests[CRYPTO[name]] for name in crypto}
    return done


__all__ = ["DATA_PASSES", "CHANNELS", "CRYPTO", "MANIFEST", "BACKGROUND_DEPTH",
           "parse_passes", "View", "Motion",
           "shape_key", "view_depth", "placed", "render_data_passes", "to_world_of", "parallel"]
