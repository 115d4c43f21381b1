"""The named choices the kernel offers, which the settings parse and the kernel reads: feature-line
tests and modes with the parsed line group (`LineSettings`; kernel/lines.py), emitter-sampling modes
(kernel/emitter_sampler.py), the sampler styletrace's own scenes use
(kernel/owen_sobol_sampler.py)."""
from __future__ import annotations

from dataclasses import dataclass

TESTS = ("silhouette", "boundary", "crease", "albedo", "depth")
DEFAULT_TESTS = ("silhouette", "boundary", "crease", "depth")
MODES = ("absorb", "expectation", "lifted")


@dataclass(frozen=True)
class LineSettings:
    """Parsed in `settings.parse` from the `line_*` integrator properties, whose declarations
    (`settings.PROPERTIES`) hold the defaults, bounds and docs: none are repeated here."""
    width: float            # pixels, the line's full width
    samples: int            # N auxiliary rays per edge
    depth: int              # edges 0 .. depth - 1 (1: the camera ray only)
    tests: tuple[str, ...]
    crease: float
    albedo: float
    slope: float
    color: tuple[float, float, float]
    gradient: tuple | None  # ((r,g,b), (r,g,b), y0 or None, y1 or None)
    objects: tuple[str, ...]
    mode: str               # "absorb", "expectation" (LLaT): k stencil pairs, or "lifted"
    k: int
    types: tuple = ()       # lifted: the line dictionary (config/line_types.LineType)
    diffuse: bool = False   # lifted: auxiliary paths go on through diffuse vertices

    def describe(self) -> str:
        if self.mode == "lifted":
            kinds = ",".join(t.measurement for t in self.types)
            return f"lines(lifted, depth={self.depth}, types={kinds})"
        return (f"lines(width={self.width}, samples={self.samples}, depth={self.depth}, "
                f"tests={','.join(self.tests)})")


#: the sampler of the built-in scenes, Blender's exporter and viewport: a padded Owen-scrambled
#: Sobol sequence per pixel (kernel/owen_sobol_sampler.py); a scene file's own is kept
SAMPLER_DEFAULT = "owen_sobol"
#: the samplers a built-in scene can be asked for: the default, and independent numbers (the
#: paper's protocols; the images of renders before the default changed)
SAMPLERS = (SAMPLER_DEFAULT, "independent")

#: next-event estimation's choice of light (kernel/emitter_sampler.py); `auto`: `spatial` where
#: the scene's sampler is `owen_sobol` and it has several emitters, else `uniform` (so a scene that
#: asks for independent samples renders as before, bit for bit)
EMITTER_MODES = ("auto", "uniform", "power", "spatial")
EMITTER_DEFAULT = "auto"
