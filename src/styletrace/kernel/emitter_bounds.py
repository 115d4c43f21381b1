"""What spatial emitter selection knows of each emitter, worked out once on the host: where it is
(a bounding sphere), which way it can shine (a cone of normals or beam directions and how far past
them light leaves), and how strong it is (a peak radiant intensity, or for lights at infinity an
irradiance). Design: docs/design/spatial_emitter_selection.md.

Kinds:
- `FINITE`: area lights (the shape's bounding box; the cone bounds every normal their emission is
  tested against), point and spot lights (their position; a spot's beam is its cutoff cone) and
  any other emitter at a finite place (the box of its `sample_ray` origins, shining everywhere).
- `ENVIRONMENT`: an emitter at infinity that is not a delta in direction (`envmap`, `constant`).
- `DIRECTIONAL`: a delta in direction at infinity (`directional`, a sun).

Only the cones may make an emitter unreachable from a point (`cone + spread` below), so they are
conservative: exact normals of rectangles, disks and meshes widened by ANGLE_MARGIN, a spot's exact
cutoff widened alike, and no cone at all (`cone = pi`) for everything else. Positions and
intensities only weigh, so estimates do for them.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from styletrace.gate import dr, mi

FINITE, ENVIRONMENT, DIRECTIONAL = 0, 1, 2

#: samples of `sample_ray` per emitter for the power and position estimates (fixed, so that they
#: are deterministic)
POWER_SAMPLES = 1 << 12
#: radians added to every cone that can exclude points: covers float32 rounding of the normals
#: and of the per-lane angle arithmetic (about 1e-6 rad) a thousand times over
ANGLE_MARGIN = 1e-3


@dataclass(frozen=True)
class EmitterBounds:
    """One emitter as spatial selection sees it (module docstring).

    kind: FINITE, ENVIRONMENT or DIRECTIONAL. center, radius: a sphere holding every point that
    emits (FINITE; zeros otherwise). axis: the cone's axis, a unit vector (FINITE), or the direction
    a DIRECTIONAL emitter's light travels. cone: the half-angle (radians, margin included) around
    axis holding every normal (area lights) or beam direction (spots); pi: any. spread: how far from
    its normal light may leave (pi/2 for area lights, 0 for points and spots). intensity: a FINITE
    emitter's peak radiant intensity estimate (W/sr, from its power), an ENVIRONMENT's mean
    irradiance pi L, a DIRECTIONAL's irradiance E (W/m^2), all >= 0.
    """
    kind: int
    center: tuple
    radius: float
    axis: tuple
    cone: float
    spread: float
    intensity: float


def _point(x) -> tuple:
    return tuple(float(c) for c in x)


def bounding_cone(normals: np.ndarray) -> tuple[tuple, float]:
    """A cone holding unit vectors: the axis along their mean, the half-angle the widest of them
    makes with it, plus ANGLE_MARGIN; no cone (pi) where that reaches a hemisphere (a cap wider than
    a hemisphere need not hold the normalised blends of its vectors, which meshes interpolate).

    Args:
        normals: N x 3 unit vectors, N >= 1.

    Returns:
        (axis as a 3-tuple, half-angle in radians).
    """
    mean = normals.mean(axis=0)
    length = float(np.linalg.norm(mean))
    if not length > 1e-6:
        return (0.0, 0.0, 1.0), math.pi
    axis = mean / length
    widest = float(np.arccos(np.clip(normals @ axis, -1.0, 1.0)).max()) + ANGLE_MARGIN
    if widest >= math.pi / 2:
        return _point(axis), math.pi
    return _point(axis), widest


def mesh_normals(mesh) -> np.ndarray:
    """Every normal a mesh's emission can be tested against: its faces' geometric normals and, if
    it has them, its vertex normals (Mitsuba interpolates those into shading normals), negated
    where the mesh flips its normals.

    Args:
        mesh: a mesh shape (`Shape.is_mesh()`; `Emitter.get_shape` hands it out as an mi.Shape).

    Returns:
        N x 3 unit vectors (float64), degenerate faces left out; maybe empty.
    """
    params = mi.traverse(mesh)
    v = np.asarray(params["vertex_positions"], dtype=np.float64).reshape(-1, 3)
    f = np.asarray(params["faces"], dtype=np.int64).reshape(-1, 3)
    n = np.cross(v[f[:, 1]] - v[f[:, 0]], v[f[:, 2]] - v[f[:, 0]])
    length = np.linalg.norm(n, axis=1)
    out = [n[length > 0] / length[length > 0, None]]
    if "vertex_normals" in params:  # empty without vertex normals
        vn = np.asarray(params["vertex_normals"], dtype=np.float64).reshape(-1, 3)
        length = np.linalg.norm(vn, axis=1)
        out.append(vn[length > 0] / length[length > 0, None])
    normals = np.concatenate(out)
    return -normals if mesh.has_flipped_normals() else normals


def area_cone(shape) -> tuple[tuple, float]:
    """The cone of an area light's normals: a rectangle's or disk's one normal (as its
    `sample_position` reports it, flipped or not), a mesh's `bounding_cone`, none for other shapes.

    Args:
        shape: the emitter's mi.Shape.

    Returns:
        (axis, half-angle in radians, margin included).
    """
    kind = shape.shape_type()
    if kind in (int(mi.ShapeType.Rectangle), int(mi.ShapeType.Disk)):
        n = shape.sample_position(0.0, mi.Point2f(0.5, 0.5)).n
        axis = np.array([float(dr.ravel(c)[0]) for c in (n.x, n.y, n.z)])
        return _point(axis / np.linalg.norm(axis)), ANGLE_MARGIN
    if shape.is_mesh():
        normals = mesh_normals(shape)
        if len(normals):
            return bounding_cone(normals)
    return (0.0, 0.0, 1.0), math.pi


def ray_samples(emitter: mi.Emitter, n: int = POWER_SAMPLES):
    """Origins, directions and weights of `n` fixed `sample_ray` samples (values Mitsuba returns
    as one constant are repeated `n` times).

    Args:
        emitter: an emitter of the scene. n: how many.

    Returns:
        (n x 3 origins, n x 3 directions, n weights averaged over the channels), float64 arrays.
    """
    rng = mi.PCG32(n, initseq=dr.arange(mi.UInt64, n))
    u = [rng.next_float32() for _ in range(5)]
    ray, weight = emitter.sample_ray(0.0, u[0], mi.Point2f(u[1], u[2]), mi.Point2f(u[3], u[4]))
    w = mi.Color3f(weight)

    def lanes(x):
        return np.broadcast_to(np.asarray(x, dtype=np.float64).reshape(-1), (n,))

    o = np.stack([lanes(c) for c in (ray.o.x, ray.o.y, ray.o.z)], axis=1)
    d = np.stack([lanes(c) for c in (ray.d.x, ray.d.y, ray.d.z)], axis=1)
    return o, d, (lanes(w.x) + lanes(w.y) + lanes(w.z)) / 3.0


def emitted_power(emitter: mi.Emitter) -> float:
    """Phi estimated as the mean weight of POWER_SAMPLES fixed `sample_ray` samples (averaged over
    the channels; non-finite weights count 0). A weight Mitsuba returns as one constant counts once
    per sample, so that emitters of every kind compare (the `power` mode's estimate once divided
    such a constant by POWER_SAMPLES: a spot outweighed an area light 4000 times).

    Args:
        emitter: an emitter of the scene.

    Returns:
        float, >= 0.
    """
    _, _, w = ray_samples(emitter)
    return max(float(np.where(np.isfinite(w), w, 0.0).mean()), 0.0)


def spot_cone(emitter: mi.Emitter) -> tuple[tuple, float] | None:
    """A Mitsuba spot light's beam: the axis its `to_world` turns +Z to and its cutoff angle (it
    emits nothing beyond), widened by ANGLE_MARGIN.

    Args:
        emitter: any emitter.

    Returns:
        (axis, half-angle in radians), or None for an emitter that is not a spot light.
    """
    if emitter.class_name() != "SpotLight":
        return None
    params = mi.traverse(emitter)
    m = np.asarray(params["to_world"].matrix, dtype=np.float64).reshape(4, 4)
    axis = m[:3, 2] / np.linalg.norm(m[:3, 2])
    cutoff = math.radians(float(dr.ravel(params["cutoff_angle"])[0]))
    return _point(axis), min(cutoff + ANGLE_MARGIN, math.pi)


def lambertian_solid_angle(cone: float) -> float:
    """Power over peak intensity of a surface of constant radiance whose normals fill a cone:
    pi for a flat one, 4 pi for a sphere, between them linearly in 1 - cos(cone) (an estimate;
    it only weighs).

    Args:
        cone: the normals' half-angle (radians, <= pi).

    Returns:
        Steradians.
    """
    return math.pi * (1.0 + 1.5 * (1.0 - math.cos(cone)))


def emitter_bounds(emitter: mi.Emitter, scene_radius: float) -> EmitterBounds:
    """The bounds of one emitter (module docstring).

    Args:
        emitter: an emitter of the scene.
        scene_radius: the radius of the scene's bounding sphere (`Scene.bbox`), > 0: Mitsuba's
            lights at infinity report the power through a disk of that radius.

    Returns:
        EmitterBounds.
    """
    phi = emitted_power(emitter)
    flags = emitter.flags()
    if mi.has_flag(flags, mi.EmitterFlags.Infinite) or mi.has_flag(
        flags, mi.EmitterFlags.DeltaDirection
    ):
        disk = math.pi * scene_radius * scene_radius
        if mi.has_flag(flags, mi.EmitterFlags.DeltaDirection):
            _, d, _ = ray_samples(emitter, 1)
            axis = _point(d[0] / np.linalg.norm(d[0]))
            return EmitterBounds(DIRECTIONAL, (0.0, 0.0, 0.0), 0.0, axis, math.pi, 0.0, phi / disk)
        # Phi = pi R^2 x the integral of L over the sphere = 4 pi^2 R^2 L_mean: pi L_mean is the
        # irradiance a surface receives from the mean environment
        return EmitterBounds(ENVIRONMENT, (0.0, 0.0, 0.0), 0.0, (0.0, 0.0, 1.0), math.pi, 0.0,
                             phi / (4.0 * disk))
    shape = emitter.get_shape()
    if shape is not None:
        box = shape.bbox()
        lo, hi = np.array(box.min, dtype=np.float64), np.array(box.max, dtype=np.float64)
        axis, cone = area_cone(shape)
        return EmitterBounds(FINITE, _point((lo + hi) / 2), float(np.linalg.norm(hi - lo)) / 2,
                             axis, cone, math.pi / 2, phi / lambertian_solid_angle(cone))
    o, _, _ = ray_samples(emitter)
    lo, hi = o.min(axis=0), o.max(axis=0)
    center, radius = _point((lo + hi) / 2), float(np.linalg.norm(hi - lo)) / 2
    beam = spot_cone(emitter)
    if beam is not None:
        axis, cone = beam
        # a spot of peak intensity I emits at most I 2 pi (1 - cos cutoff)
        solid = 2.0 * math.pi * (1.0 - math.cos(min(cone, math.pi)))
        return EmitterBounds(FINITE, center, radius, axis, cone, 0.0, phi / solid)
    return EmitterBounds(FINITE, center, radius, (0.0, 0.0, 1.0), math.pi, 0.0,
                         phi / (4.0 * math.pi))
