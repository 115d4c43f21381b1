"""The named choices the kernel offers, which the settings parse and the kernel reads: feature-line tests and
modes with the parsed line group (`LineSettings`; kernel/lines.py), emitter-sampling modes
(kernel/emitter_sampler.py)."""
from __future__ import annotations

from dataclasses import dataclass

TESTS = ("silhouette", "boundary", "crease", "albedo", "depth")
DEFAULT_TESTS = ("silhouette", "boundary", "crease", "depth")
MODES = ("absorb", "expectation")


@dataclass(frozen=True)
class LineSettings:
    """Parsed in `settings.parse` from the `line_*` integrator properties, whose declarations
    (`settings.PROPERTIES`) hold the defaults, bounds and docs: none are repeated here."""
    width: float                             # pixels, the line's full width
    samples: int                             # N auxiliary rays per edge
    depth: int                               # edges 0 .. depth - 1 (1: the camera ray only)
    tests: tuple[str, ...]
    crease: float
    albedo: float
    slope: float
    color: tuple[float, float, float]
    gradient: tuple | None                   # ((r,g,b), (r,g,b), y0 or None, y1 or None)
    objects: tuple[str, ...]
    mode: str                                # "absorb" or "expectation" (LLaT): k stencil pairs
    k: int

    def describe(self) -> str:
        return (f"lines(width={self.width}, samples={self.samples}, depth={self.depth}, tests={','.join(self.tests)})")


EMITTER_MODES = ("uniform", "power")
EMITTER_DEFAULT = "uniform"
