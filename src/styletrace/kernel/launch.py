"""One launch of Mitsuba's render loop that leaves the scene's sampler as it was.

    img = render_pass(scene, integrator, spp=4, seed=7)     # mi.render's image, evaluated
    img = render_pixel_pass(scene, integrator, spp=4, seed=7)  # each sample kept in its pixel

Mitsuba's render loop sets the sensor's own sampler to the launch's sample count, so a scene
rendered in passes of one camera sample would say afterwards that its file asked for one: the
next render of the same scene object would take another default budget (`samples`, the scene's
sample count: `scene.loading.scene_spp`). Every launch of the project's goes through
`render_pass`, which puts the count back once the image is evaluated.

`render_pixel_pass` is the image of a box filter whatever the film's: each camera sample counts
in its own pixel only. A tent or gaussian filter spreads a sample over neighbouring pixels, which
correlates the image's noise; the image denoiser needs it uncorrelated (docs/look.md, "Clean where
the light is hard").
"""
from __future__ import annotations

import contextlib

from styletrace.gate import dr, mi
from styletrace.kernel.owen_sobol_sampler import OwenSobolSampler, Sequence

#: Camera samples per pass: bounds the memory of the megakernel's state (~ a few hundred
#: bytes each).
LANES_PER_PASS = 1 << 20


def pass_seed(seed: int, index: int) -> int:
    """Seed of pass `index`: distinct passes and distinct user seeds get unrelated sample streams.

    Args:
        seed: the render's seed. index: the launch number (round * tiles + tile).

    Returns:
        A 32-bit seed.
    """
    return (seed * 0x9E3779B1 + index * 0x85EBCA6B + 0x27D4EB2F) & 0xFFFFFFFF


@contextlib.contextmanager
def in_sequence(sensor, sequence: Sequence | None):
    """While the context lasts, an `owen_sobol` sampler of the sensor continues `sequence` (other
    samplers: nothing changes).

    Args:
        sensor: the mi.Sensor. sequence: the launch's place in its render's sequence; None: the
            launch is a sequence of its own.
    """
    sampler = sensor.sampler()
    if not isinstance(sampler, OwenSobolSampler):
        yield
        return
    before = sampler.sequence
    sampler.sequence = sequence
    try:
        yield
    finally:
        sampler.sequence = before


def render_pass(scene: mi.Scene, integrator, spp: int, seed: int,
                sequence: Sequence | None = None):
    """`mi.render(scene, integrator=integrator, spp=spp, seed=seed)`, evaluated, with the first
    sensor's sampler left at its own sample count.

    Args:
        scene: the scene (its first sensor renders). integrator: the integrator to launch.
        spp: camera samples per pixel of this launch. seed: its seed.
        sequence: where the launch sits in its render's sequence (`owen_sobol` samplers only);
            None: a sequence of its own, keyed by `seed`.

    Returns:
        mi.render's image (a TensorXf), evaluated.
    """
    sensor = scene.sensors()[0]
    sampler = sensor.sampler()
    count = int(sampler.sample_count())
    try:
        with in_sequence(sensor, sequence):
            img = mi.render(scene, integrator=integrator, spp=int(spp), seed=int(seed))
            dr.eval(img)
        return img
    finally:
        sampler.set_sample_count(count)


def seeded_positions(sensor, spp: int, seed: int, border: int = 0, offset=(0, 0)):
    """Seed a clone of the sensor's sampler as Mitsuba's render loop does, and place each lane.

    Args:
        sensor: the mi.Sensor; its film's crop size and its sampler are read.
        spp, seed: the pass's camera samples per pixel and seed.
        border: pixels added on each side of the crop window (where the film samples its border).
        offset: integer (x, y) added to each pixel corner (the crop offset), as Mitsuba adds it.

    Returns:
        (the seeded sampler, whose next draws are the aperture's and the integrator's; each lane's
        film position, mi.Vector2f): lane i is pixel i // spp, its corner plus the first next_2d().
    """
    w, h = (int(v) + 2 * border for v in sensor.film().crop_size())
    lanes = w * h * spp
    sampler = sensor.sampler().clone()
    sampler.set_sample_count(spp)
    sampler.set_samples_per_wavefront(spp)
    sampler.seed(seed, lanes)
    idx = dr.arange(mi.UInt32, lanes) // spp
    py = idx // w
    px = idx - py * w
    corner = mi.Vector2i(mi.Int32(px) + (int(offset[0]) - border),
                         mi.Int32(py) + (int(offset[1]) - border))
    return sampler, mi.Vector2f(corner) + sampler.next_2d()


def render_pixel_pass(scene: mi.Scene, integrator, spp: int, seed: int,
                      sequence: Sequence | None = None):
    """The mean of `spp` camera samples inside each pixel of the film's crop window, as a film with
    a box filter would develop them: Mitsuba's render loop's rays (its sampler seeded alike, the
    aperture, shutter and differential scaling as it draws them), `integrator.sample` on each.

    Args:
        scene: the scene (its first sensor renders, its film's crop window as set now).
        integrator: a sampling integrator whose `sample` is the whole of its render (not one that
            replaces `render`, such as reuse=pixels).
        spp: camera samples per pixel of this launch. seed: its seed.
        sequence: as `render_pass`'s.

    Returns:
        H x W x 3 float32 numpy array, RGB.
    """
    import numpy as np

    sensor = scene.sensors()[0]
    film = sensor.film()
    (w, h), offset = (int(v) for v in film.crop_size()), [int(v) for v in film.crop_offset()]
    # the seed as a kernel input, as Mitsuba's loop has it: each pass reuses the compiled kernel
    with in_sequence(sensor, sequence):
        sampler, pos = seeded_positions(sensor, int(spp), dr.opaque(mi.UInt32, int(seed)), 0,
                                        offset)
    aperture = sampler.next_2d() if sensor.needs_aperture_sample() else mi.Point2f(0.5)
    time = mi.Float(sensor.shutter_open())
    if sensor.shutter_open_time() > 0.0:
        time += sampler.next_1d() * sensor.shutter_open_time()
    # the crop window's [0, 1]^2, as Mitsuba's loop maps a film position
    at = (mi.Point2f(pos) - mi.ScalarVector2f(offset)) / mi.ScalarVector2f(w, h)
    ray, weight = sensor.sample_ray_differential(time, mi.Float(0.0), at, aperture)
    ray.scale_differential(dr.rsqrt(float(spp)))
    value, _, _ = integrator.sample(scene, sampler, ray, sensor.get_medium())
    value = value * weight
    dr.eval(value)  # one kernel for the three channels: each block sum would launch its own
    # a pixel's lanes are next to each other (`seeded_positions`)
    means = [dr.block_sum(value[c], int(spp)) / float(spp) for c in range(3)]
    dr.eval(means)
    return np.stack([np.asarray(m, dtype=np.float32) for m in means], -1).reshape(h, w, 3)


__all__ = ["LANES_PER_PASS", "pass_seed", "in_sequence", "render_pass", "render_pixel_pass",
           "seeded_positions"]
