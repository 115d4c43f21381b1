"""The sample budget: a render's paths per pixel split into camera samples and children.

    s = split(Request(samples=16, spp=None, inner=None, default=16, denoised=True))
    s.spp, s.inner, s.paths, s.note     # 4, (4,), 16, "samples=16: spp=4 x 4 children"

`samples` is what Cycles calls Samples: paths per pixel, whatever the style. A camera sample of a
style with n children costs n paths (the product over the stylized levels; a closed-form style,
with no children, one). The rule (chosen by measurement; docs/look.md):

- neither spp nor inner given: n = min(the style's default n, CHILDREN, samples) for one stylized
  level where the expectation is denoised before g (every front end's default for a style of
  several children), n = min(the style's default n, samples) where it is not (g applied to each
  camera sample's mean of n children is biased by O(1/n)); several levels keep their defaults;
  spp = max(1, round(samples / P));
- inner given: spp = max(1, round(samples / P));
- spp given: n = max(1, round(samples / spp)) for one level where samples was given too, else the
  style's default (the render of every call before samples existed);
- both given: as given; with samples given as well they must agree (spp x P = samples).

P is the product of the levels' counts (an adaptive count n0:n_max counts n0). A cap on camera
samples (the expectation buffer's) lowers an auto spp and raises an auto n to ceil(samples / spp);
a floor (the error AOVs' variance needs 2 camera samples) raises an auto spp and lowers an auto n
to max(1, round(samples / spp)).
`pipeline.resolve` asks for the split of every render; the preview asks for its own.
Design: docs/look.md, "The sample budget".
"""
from __future__ import annotations

import math
from dataclasses import dataclass

from styletrace.errors import UsageError

#: the most children an auto split gives a camera sample. Measured at equal samples (16 and 64)
#: on three interiors and exteriors: 2 to 4 children per camera sample gave the least noise between
#: seeds with the expectation denoised, 16 the most (3 to 5 dB more), at about equal time; and
#: camera samples of few children let a viewport show a clean image after its first, cheap pass
#: (docs/design/sample_budget.md)
CHILDREN = 4


@dataclass(frozen=True)
class Request:
    """What a render's caller and scene said about its cost.

    Args:
        samples: the budget, paths per pixel (the caller's, else the scene's sample count).
        spp: camera samples per pixel given, or None (chosen here).
        inner: children per stylized level given (the caller's or the scene file's), or None.
        default: the style's default n (`Style.default_inner`; 0 for a closed-form style or an
            integrator without children).
        levels: the stylized levels (`stylize_depth`).
        samples_given: whether the caller named `samples` (the scene's count is a default only).
        min_spp: the fewest camera samples an auto spp may take (2 where the error AOVs estimate
            each pixel's variance).
        denoised: the expectation is denoised before g (`denoise.default.pin_denoise_budget`
            says so), so an auto n is at most CHILDREN; False (what `pipeline.resolve` asks):
            g meets each camera sample's mean, and an auto n is the style's.
    """
    samples: int
    spp: int | None
    inner: tuple[int, ...] | None
    default: int
    levels: int = 1
    samples_given: bool = False
    min_spp: int = 1
    denoised: bool = False

    @property
    def closed(self) -> bool:
        """Whether a camera sample draws no children (one path each, whatever n says)."""
        return self.default == 0


@dataclass(frozen=True)
class Split:
    """A request's camera samples and children.

    Args:
        request: what was asked. spp: camera samples per pixel. inner: children per stylized
            level (one count for every level, or one per level).
    """
    request: Request
    spp: int
    inner: tuple[int, ...]

    @property
    def paths(self) -> int:
        """Paths per pixel: spp x P."""
        return self.spp * paths_per_camera_sample(self.inner, self.request)

    @property
    def chosen(self) -> bool:
        """Whether the budget chose anything (spp, or n where samples was given with spp)."""
        r = self.request
        return r.spp is None or (r.inner is None and r.samples_given and one_level(r))

    @property
    def note(self) -> str:
        """The `auto` line's words for the split ('' where the caller gave every count)."""
        if not self.chosen:
            return ""
        r = self.request
        head = f"samples={r.samples}: spp={self.spp}"
        if r.closed:
            return f"{head} (no children)"
        if r.levels == 1:
            n = self.inner[0]
            return f"{head} x {n} {'child' if n == 1 else 'children'}"
        # several levels: each level's count, as --inner spells them, and what they multiply to
        counts = ",".join(str(self.inner[min(k, len(self.inner) - 1)]) for k in range(r.levels))
        return f"{head} x {counts} children ({self.paths} paths per pixel)"


def one_level(request: Request) -> bool:
    """Whether the budget chooses n: one stylized level of a style with children."""
    return request.levels == 1 and not request.closed


def paths_per_camera_sample(inner: tuple[int, ...], request: Request) -> int:
    """P: the product of the stylized levels' children counts (1 without children).

    Args:
        inner: the counts, one for every level or one per level (adaptive: n0).
        request: the request (its levels, whether the style is closed-form).

    Returns:
        P >= 1.
    """
    if request.closed:
        return 1
    return math.prod(max(1, int(inner[min(level, len(inner) - 1)]))
                     for level in range(request.levels))


def split(request: Request, cap: int | None = None) -> Split:
    """The rule (the module doc): the camera samples and children of a request.

    Args:
        request: the budget and the counts given.
        cap: the most camera samples per pixel an auto spp may take (the expectation buffer's),
            or None.

    Returns:
        The Split.

    Raises:
        UsageError: samples, spp and inner all given and spp x P != samples (one line).
    """
    r = request
    default = (max(r.default, 1),)
    inner = r.inner if r.inner is not None else default
    if r.inner is None and one_level(r):
        if r.spp is None:
            most = CHILDREN if r.denoised else default[0]
            inner = (min(default[0], most, r.samples),)
        elif r.samples_given:
            inner = (max(1, round(r.samples / r.spp)),)
    per = paths_per_camera_sample(inner, r)
    if r.spp is not None:
        if r.inner is not None and r.samples_given and r.spp * per != r.samples:
            counts = ",".join(str(c) for c in r.inner)
            raise UsageError(
                f"--samples {r.samples} with --spp {r.spp} and --inner {counts} ({r.spp * per} "
                f"paths per pixel): give at most two of the three"
            )
        return Split(r, r.spp, inner)
    spp = max(1, round(r.samples / per))
    if spp < r.min_spp:
        spp = r.min_spp
        if r.inner is None and one_level(r):
            inner = (max(1, round(r.samples / spp)),)
    if cap is not None and spp > cap:
        spp = max(1, cap)
        if r.inner is None and one_level(r):
            inner = (math.ceil(r.samples / spp),)
    return Split(r, spp, inner)


__all__ = ["Request", "Split", "split", "paths_per_camera_sample", "one_level", "CHILDREN"]
