"""One launch of Mitsuba's render loop that leaves the scene's sampler as it was.

    img = render_pass(scene, integrator, spp=4, seed=7)     # mi.render's image, evaluated

Mitsuba's render loop sets the sensor's own sampler to the launch's sample count, so a scene
rendered in passes of one camera sample would say afterwards that its file asked for one: the
next render of the same scene object would take another default budget (`samples`, the scene's
sample count: `scene.loading.scene_spp`). Every launch of the project's goes through
`render_pass`, which puts the count back once the image is evaluated.
"""
from __future__ import annotations

from styletrace.gate import dr, mi


def render_pass(scene: mi.Scene, integrator, spp: int, seed: int):
    """`mi.render(scene, integrator=integrator, spp=spp, seed=seed)`, evaluated, with the first
    sensor's sampler left at its own sample count.

    Args:
        scene: the scene (its first sensor renders). integrator: the integrator to launch.
        spp: camera samples per pixel of this launch. seed: its seed.

    Returns:
        mi.render's image (a TensorXf), evaluated.
    """
    sampler = scene.sensors()[0].sampler()
    count = int(sampler.sample_count())
    try:
        img = mi.render(scene, integrator=integrator, spp=int(spp), seed=int(seed))
        dr.eval(img)
        return img
    finally:
        sampler.set_sample_count(count)


__all__ = ["render_pass"]
