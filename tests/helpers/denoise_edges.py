"""What the denoiser's edge tests share (tests/denoise/test_texture_edges.py,
test_emitter_edges.py): a denoised identity render of a scene, the samples where it applied the
style (its camera samples with coverage 0, else its coverage points: `denoise.coverage`), each
sample's own albedo and emission, and the pixels whose samples fall on both sides of an edge."""

from dataclasses import dataclass

import numpy as np

from styletrace.denoise import expectation as X
from styletrace.frontends import api
from styletrace.pipeline.denoising import Denoising
from styletrace.pipeline.passes import Shot


@dataclass
class Samples:
    # the buffer's per-sample arrays (D: `denoised_mean`, or `mean` for coverage points)
    arrays: dict
    albedo: np.ndarray  # N x 3, each sample's own (`own_surface`)
    emission: np.ndarray  # N x 3
    pixel: np.ndarray  # N, int64
    found: np.ndarray  # N, a stylized vertex was recorded

    def denoised(self, channel: int = 0) -> np.ndarray:
        return self.arrays[X.DENOISED if X.DENOISED in self.arrays else "mean"][channel]

    def in_pixels_with_both(
        self, side_a: np.ndarray, side_b: np.ndarray, size: int
    ) -> tuple[int, np.ndarray]:
        """(how many pixels hold samples of both sides, per sample: its pixel is one of them)."""
        a = np.bincount(self.pixel, weights=side_a, minlength=size) > 0
        b = np.bincount(self.pixel, weights=side_b, minlength=size) > 0
        both = a & b
        return int(both.sum()), both[self.pixel]


def denoised_identity(
    scene, spp: int = 8, inner: int = 4, seed: int = 2, coverage: int = 0
) -> Samples:
    _, buf = X.render_denoised_expectation(
        Shot(scene, api.make_integrator(style="identity", inner=inner), spp, seed),
        Denoising("expectation", coverage=coverage),
    )
    a = buf.arrays
    albedo, emission = X.own_surface(scene, a)
    return Samples(a, albedo, emission, a["pixel"].astype(np.int64), a["slot"] >= 0)
