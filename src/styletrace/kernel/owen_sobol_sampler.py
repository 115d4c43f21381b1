"""The `owen_sobol` Mitsuba sampler: a padded Owen-scrambled Sobol sequence per pixel, for the
camera ray and, in the `stylized` integrator, every decision of the path below it.

    <sampler type="owen_sobol"><integer name="sample_count" value="64"/></sampler>
    {"type": "owen_sobol", "sample_count": 64}

Mitsuba's render loop seeds it and draws the camera sample from it (film position, aperture,
time); the `stylized` integrator then takes the lanes' sequences (`lanes`) from the next dimension
on (`sequence_sampler.SequenceSampler`). Lane i of a launch of spp camera samples per pixel is
sample offset + i mod spp of pixel i // spp (Mitsuba's pixel-major layout). A render in passes
continues one sequence: the pass loop tells the sampler the seed of the render's first pass, the
tile and how many camera samples of the pixel came before (`Sequence`, `launch.render_pass`);
without one, a launch is a sequence of its own, keyed by its seed.

Other integrators (Mitsuba's `path`) draw from it as from any Mitsuba sampler: its lanes' state
is a Dr.Jit struct, which their symbolic loops carry, so each bounce draws new dimensions
(tests/kernel/test_owen_sobol_sampler.py renders the Cornell box with `path` both ways).
Design: docs/design/sequence_sampler.md.
"""
from __future__ import annotations

from dataclasses import dataclass

from styletrace.gate import dr, mi
from styletrace.kernel.sequence_sampler import SequenceSampler, counter, pixel_key

#: the plugin's name in scene files and dicts
NAME = "owen_sobol"


@dataclass(frozen=True)
class Sequence:
    """Where a launch sits in its render's sequence.

    seed: the seed that keys the sequence, the same for every pass of a render
    (`passes.unit_sequence`: its first pass's); tile: the tile's index (its own pixels' keys);
    offset: the camera samples per pixel launched before it.
    """
    seed: int = 0
    tile: int = 0
    offset: int = 0


class OwenSobolSampler(mi.Sampler):
    """The `owen_sobol` sampler (module docstring).

    Args:
        props: Mitsuba properties: sample_count (default 4), as Mitsuba's samplers.
    """

    def __init__(self, props: mi.Properties):
        super().__init__(props)
        self.sequence: Sequence | None = None
        self._lanes = SequenceSampler()
        self._camera_dims = 0

    def seed(self, seed, wavefront_size):
        """Key each lane by its pixel and number it within the pixel (module docstring).

        Args:
            seed: the launch's seed (used where no `sequence` is set). wavefront_size: the
                launch's lanes, sample_count per pixel side by side.
        """
        super().seed(seed, wavefront_size)
        n = int(wavefront_size)
        spp = max(int(self.sample_count()), 1)
        lane = dr.arange(mi.UInt32, n)
        per_pixel = spp if n % spp == 0 else 1
        pixel = lane // per_pixel
        ctx = self.sequence
        base, tile, offset = ((mi.UInt32(seed), 0, 0) if ctx is None
                              else (mi.UInt32(ctx.seed), ctx.tile, ctx.offset))
        # the seed, tile and offset as kernel inputs: every pass reuses the compiled kernel
        dr.make_opaque(base)
        key = pixel_key(base, dr.opaque(mi.UInt32, tile), pixel)
        index = lane - pixel * per_pixel + dr.opaque(mi.UInt32, offset)
        self._lanes = SequenceSampler(key, index, counter(0, key))
        self._camera_dims = 0

    def next_1d(self, active=True):
        """The camera sample's next dimension (Mitsuba's render loop: time, wavelengths)."""
        self._camera_dims += 1
        return self._lanes.next_1d(active)

    def next_2d(self, active=True):
        """The camera sample's next dimension pair (film position, aperture)."""
        self._camera_dims += 1
        return self._lanes.next_2d(active)

    def lanes(self) -> SequenceSampler:
        """The lanes' sequences from the dimension after the camera sample's on.

        Returns:
            SequenceSampler.
        """
        lanes = self._lanes
        return SequenceSampler(lanes.key, lanes.index, counter(self._camera_dims, lanes.key),
                               counter(0, lanes.key))

    def clone(self):
        """A sampler of the same count and sequence (Mitsuba and `launch.seeded_positions` seed
        clones as the render loop seeds its own)."""
        other = OwenSobolSampler(mi.Properties())
        other.set_sample_count(self.sample_count())
        other.sequence = self.sequence
        return other

    def to_string(self):
        return f"OwenSobolSampler[sample_count={int(self.sample_count())}]"


def sequenced(scene: mi.Scene) -> bool:
    """Whether the scene's first sensor samples with `owen_sobol` (its passes continue one
    sequence, so the pass split cannot change its samples).

    Args:
        scene: the mi.Scene.

    Returns:
        bool.
    """
    sensors = scene.sensors()
    return bool(sensors) and isinstance(sensors[0].sampler(), OwenSobolSampler)


def register() -> None:
    """Register `owen_sobol` with Mitsuba for the active variant.

    Raises:
        RuntimeError: Mitsuba refuses the registration.
    """
    mi.register_sampler(NAME, lambda props: OwenSobolSampler(props))


__all__ = ["NAME", "Sequence", "OwenSobolSampler", "sequenced", "register"]
