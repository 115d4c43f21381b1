"""The reuse pass loop: a pass of `spp` camera samples per pixel rendered in batches, each splatted
onto one block.

The children of a pass are stored (16 floats each, side by side), so a pass is split into batches of
camera samples per pixel of at most BATCH_CHILDREN children. Neighbours are looked up within one
batch of one crop window (`pipeline.passes` tiles images above a million pixels; a window is clipped
at a tile's edge).
"""
from __future__ import annotations

from dataclasses import replace

from styletrace.config import settings as S
from styletrace.errors import SceneError
from styletrace.gate import dr, mi
from styletrace.jit import no_collection
from styletrace.kernel.render_context import RenderContext
from styletrace.kernel.reuse_batch import Samples, batch
from styletrace.kernel.reuse_pool import Frame
from styletrace.kernel.reuse_scope import Scope, children_per_lane

#: children stored per batch of a pass (64 MB of child data)
BATCH_CHILDREN = 1 << 20


def batch_seed(seed: int, batch: int) -> int:
    """The sampler seed of a batch of a pass: the pass's own seed for batch 0, else a hash of both.

    Args:
        seed: the pass's seed. batch: the batch's index in the pass.

    Returns:
        A seed below 2^32.
    """
    return (
        seed if batch == 0 else (seed * 0x9E3779B1 + batch * 0x85EBCA6B + 0x165667B1) & 0xFFFFFFFF
    )


def render_reuse(
    integ,
    scene: mi.Scene,
    sensor: mi.Sensor,
    seed: int,
    spp: int,
    weights: str | None = None,
    keep: dict | None = None,
) -> mi.TensorXf:
    """The developed film (mi.TensorXf) of one pass rendered with reuse=pixels, as `mi.render`.

    Args:
        integ, scene, sensor: the `stylized` integrator (bound to scene here), scene, its sensor.
        seed, spp: the pass's seed and camera samples per pixel.
        weights: overrides `reuse_mis` ('balance', 'pairwise'); 'own' divides each pooled BSDF
            sample by its own density (wrong: the tests' negative control).
        keep: a dict that receives the first batch's pools as numpy arrays (`pool_pixels`).

    Raises:
        SceneError: the scene has media or null-scattering surfaces, or its styling is refused.
        SettingsError: a styled BSDF's style cannot take reuse (`settings.check_reusable`).
    """
    # no scene may be finalised while a pass is recorded (jit.no_collection); the render context
    # binds targets, emitters and view to this scene and releases them after
    with no_collection(), RenderContext(integ, scene):
        if integ.nulls or integ.media:
            what = (
                "participating media"
                if integ.media
                else "null-scattering surfaces (masks, null BSDFs)"
            )
            raise SceneError(
                f"reuse=pixels does not support scenes with {what} yet: render with reuse=off"
            )
        for t in integ.targets:
            if t.bsdfs:
                S.check_reusable(
                    t.slot,
                    f"a styled BSDF's style '{t.slot.style.name}'",
                    integ.settings.reuse_deep,
                )
            t.slot.style.prepare(scene)
        return _passes(
            Scope.of(integ, scene, weights or integ.settings.reuse_mis, keep), sensor, seed, spp
        )


def _passes(scope: Scope, sensor, seed: int, spp: int):
    film = sensor.film()
    film.prepare([])
    size = film.crop_size()
    if film.sample_border():
        size += 2 * film.rfilter().border_size()
    width, height = int(size[0]), int(size[1])
    M = children_per_lane(scope.targets)
    stored = (
        M * (1 + children_per_lane(scope.targets, 1)) if scope.settings.reuse_deep == "world" else M
    )
    per_batch = max(1, min(spp, BATCH_CHILDREN // max(width * height * stored, 1)))
    block = film.create_block()
    done, index = 0, 0
    while done < spp:
        n = min(per_batch, spp - done)
        here = scope if index == 0 else replace(scope, keep=None)
        _splat(
            block, film, batch(here, sensor, Frame(width, height, n), batch_seed(seed, index), spp)
        )
        dr.eval(block.tensor())
        done, index = done + n, index + 1
    film.put_block(block)
    return film.develop()


def _splat(block, film, samples: Samples):
    value, valid, pos, wavelengths = samples.value, samples.valid, samples.pos, samples.wavelengths
    alpha = dr.select(valid, mi.Float(1.0), mi.Float(0.0))
    if dr.all(mi.has_flag(film.flags(), mi.FilmFlags.Special)):
        block.put(
            pos,
            film.prepare_sample(value, wavelengths, block.channel_count(), weight=1.0, alpha=alpha),
        )
    elif mi.has_flag(film.flags(), mi.FilmFlags.Alpha):
        block.put(pos, [value.x, value.y, value.z, alpha, mi.Float(1.0)])
    else:
        block.put(pos, [value.x, value.y, value.z, mi.Float(1.0)])
