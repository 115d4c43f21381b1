"""Coverage points: where g is evaluated once E[L] is denoised, apart from where E[L] was estimated.

    cov = points(scene, integrator, field, k=16, seed=0)   # a Buffer of k first hits per pixel

With the expectation denoised, a pixel's value is the integral over its footprint of g(D(x)); the
camera samples with children are only one, expensive, way of placing the points x. A coverage
point is a camera ray to its first hit and nothing more (the same kernel as a render, `record`),
so many can be spent per pixel for the cost of a few children, stratified: k = m x m points, one
jittered point in each cell of an m x m grid over the pixel.
Design: docs/design/coverage_points.md.
"""
from __future__ import annotations

import math

from styletrace.denoise.probe import Probe
from styletrace.errors import UsageError
from styletrace.gate import dr, mi
from styletrace.kernel import guides
from styletrace.kernel.integrator import StylizedIntegrator
from styletrace.lookdev.buffer import MAX_CAMERA_SAMPLES, Buffer
from styletrace.lookdev.record import RecordingIntegrator, inputs, record
from styletrace.lookdev.restyle import finish_spread
from styletrace.pipeline.passes import PassSplit, Shot, pass_seed
from styletrace.scene.defaults import ScenePilot

#: points per pixel of coverage="auto" (chosen on the Cornell box, BENCHMARKS.md denoise), less
#: where the image is so large that they would not fit the buffer's cap
DEFAULT_K = 64
AUTO = "auto"
#: the pass index whose seed the coverage points use: far from any render's own passes
COVERAGE_PASS = 1 << 30


def check_k(k) -> int | str:
    """A coverage value, checked.

    Args:
        k: "auto", 0 (g at the camera samples) or a square >= 1 (an int, or its digits as text).

    Returns:
        "auto", or k as an int.

    Raises:
        UsageError: anything else (one line).
    """
    if k == AUTO:
        return AUTO
    value = k if isinstance(k, int) and not isinstance(k, bool) else None
    if isinstance(k, str) and k.strip().isdigit():
        value = int(k)
    if value is None or value < 0 or (value and math.isqrt(value) ** 2 != value):
        raise UsageError(
            f"bad value {k!r} for coverage: expected 'auto', 0 (g at the camera samples) or a "
            "square number of points per pixel (1, 4, 9, 16, 25, 36, 49, 64, ...)"
        )
    return value


def resolve_k(k, width: int, height: int, max_camera_samples: int = MAX_CAMERA_SAMPLES) -> int:
    """The points per pixel of a render.

    Args:
        k: as `check_k` takes it. width, height: the film's size.
        max_camera_samples: the buffer's cap (MAX_CAMERA_SAMPLES).

    Returns:
        For "auto" DEFAULT_K, or the largest square whose points fit the cap (0 where not even one
        does); a number given, as it is.

    Raises:
        UsageError: a bad k, or a k whose points do not fit the cap (one line).
    """
    k = check_k(k)
    pixels = max(1, width * height)
    if k == AUTO:
        return min(DEFAULT_K, math.isqrt(max_camera_samples // pixels) ** 2)
    if k * pixels > max_camera_samples:
        raise UsageError(
            f"bad value {k} for coverage: {width}x{height} at {k} points per pixel is {k * pixels} "
            f"points, over the buffer's cap of {max_camera_samples}; use at most "
            f"{math.isqrt(max_camera_samples // pixels) ** 2} or 'auto'"
        )
    return k


class CoverageIntegrator(RecordingIntegrator):
    """The recording integrator with no children, its camera rays on an m x m jittered grid per
    pixel.

    Lane i of a pass of k spp is pixel i // k's point i % k (the crop widened by the filter's
    border where the film samples it); each point's film position is kept (`pos`: a restyle splats
    it with the film's filter). The vertex's mean is D there (`expectation.Field.at`), so the pass's
    image is the denoised render (box filter) and its buffer holds D at every point.

    Args:
        base: the render's `stylized` integrator. k: points per pixel, a square. field: D and its
            guides (`expectation.Field`). origin: the film's crop offset (a tile lies at its crop
            offset minus this in D). scale: D's pixels per film pixel along each axis.
    """

    def __init__(self, base: StylizedIntegrator, k: int, field, origin=(0, 0), scale: int = 1):
        super().__init__(base)
        self.k, self.m, self.field = k, math.isqrt(k), field
        #: the film's crop offset: a tile's (`pipeline.passes`) lies at its crop offset minus this
        #: in D
        self.origin = mi.ScalarVector2f(origin)
        #: D's pixels per film pixel along each axis (1; more for a D below the pixel,
        #: benchmarks/denoise_subpixel.py); the spread stays per film pixel
        self.scale = int(scale)
        self.width = field.w // self.scale
        self._at = None

    def sample(self, scene, sampler, ray, medium=None, active=True):
        sensor = scene.sensors()[0]
        film = sensor.film()
        cw, ch = (int(v) for v in film.crop_size())
        off = mi.ScalarVector2f(film.crop_offset())
        # border sampling (a filter other than a box): the lanes cover the crop and its border
        b = int(film.rfilter().border_size()) if film.sample_border() else 0
        lane = dr.arange(mi.UInt32, dr.width(ray.d))
        pixel, cell = lane // self.k, lane % self.k
        px = mi.Float(pixel % (cw + 2 * b)) - b
        py = mi.Float(pixel // (cw + 2 * b)) - b
        cx, cy = mi.Float(cell % self.m), mi.Float(cell // self.m)
        jitter = sampler.next_2d()
        pos = mi.Point2f(px + (cx + jitter.x) / self.m, py + (cy + jitter.y) / self.m)
        wavelength = sampler.next_1d()
        aperture = sampler.next_2d()
        # the sensor's position sample spans the crop window (as SamplingIntegrator::render_sample
        # makes it)
        placed, _ = sensor.sample_ray_differential(
            mi.Float(0.0), wavelength, pos / mi.ScalarVector2f(cw, ch), aperture
        )
        on_film = mi.Point2f(pos + off)  # the point's film position: the restyle splats it there
        # (0, 0) but in a tile: D, its guides and spread are the whole film's
        shift = off - self.origin
        pos = pos + shift
        # a border point looks D up from the nearest pixel of the crop
        px, py = dr.clip(px, 0, cw - 1), dr.clip(py, 0, ch - 1)
        pixel = mi.UInt32(py + shift.y) * self.width + mi.UInt32(px + shift.x)
        self._at = (pos, pixel, None)
        try:
            out = super().sample(scene, sampler, placed, medium, active)
        finally:
            self._at = None
        self.kept["pos"] = on_film
        dr.schedule(on_film)
        return out

    def finish_mean(self, slot, m, v):
        """g averaged over D's uncertainty at the point's pixel where the field has one
        (`restyle.finish_spread`)."""
        if self.field.spread is None:
            return super().finish_mean(slot, m, v)
        _, pixel, _ = self._at
        return finish_spread(inputs(slot), m, v, dr.gather(mi.Float, self.field.spread, pixel))

    def _mean(self, slot, level, sampler, site, active) -> mi.Color3f:
        """D at the vertex in place of the children's mean (one lookup per camera ray, whatever
        the slot)."""
        pos, pixel, value = self._at
        scene, si = self.walk_config.scene, site.si
        if value is None:
            valid = si.is_valid()
            albedo, _ = guides.through_delta(scene, si, valid)
            emission = (
                mi.Color3f(si.emitter(scene, valid).eval(si, valid))
                if self.field.emission_apart
                else mi.Color3f(0.0)
            )
            at, own = pos, pixel
            if self.scale != 1:  # D's own pixel of the point
                at = pos * self.scale
                own = mi.UInt32(dr.floor(at.y)) * self.field.w + mi.UInt32(dr.floor(at.x))
            probe = Probe(at, si.p, mi.Vector3f(si.sh_frame.n), own, valid)
            value = self.field.at(probe, albedo, emission)
            self._at = (pos, pixel, value)
        return value


def points(
    scene: mi.Scene,
    integrator: StylizedIntegrator,
    field,
    k: int = DEFAULT_K,
    seed: int = 0,
    scale: int = 1,
    pilot: ScenePilot | None = None,
) -> Buffer:
    """The denoised render at k stratified points per pixel (seeded COVERAGE_PASS passes away).

    Args:
        scene, integrator, seed: the render's. field: D and its guides (`expectation.Field`).
        k: points per pixel, a square >= 1. scale: D's pixels per film pixel (1).
        pilot: the render's scene-defaults pilot (its samples go into the buffer, as the
            recording's), or None: a new one, traced here (0.4 s on a 512x512 interior).

    Returns:
        A Buffer whose means are D at each point (pixel, slot, vertex, L_before as a render's) and
        whose `image` is the pass's (`expectation.attach` restyles it for filters but a box). Its
        arrays stay on the device until read (`lookdev.buffer.Arrays`).

    Raises:
        ValueError: k is not an int >= 1.
    """
    if not isinstance(k, int) or k < 1:
        raise ValueError(f"points() needs k >= 1 points per pixel, not {k!r}")
    buf = None
    origin = tuple(int(v) for v in scene.sensors()[0].film().crop_offset())
    for prog, buf in record(
        Shot(scene, integrator, k, pass_seed(seed, COVERAGE_PASS)),
        PassSplit(pass_spp=k),
        pilot=pilot,
        recorder=lambda base, *_: CoverageIntegrator(base, k, field, origin, scale),
    ):
        buf.image = prog.image
    return buf


__all__ = ["points", "check_k", "resolve_k", "CoverageIntegrator", "DEFAULT_K", "AUTO"]
