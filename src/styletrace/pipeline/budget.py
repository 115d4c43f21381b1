"""The sample budget: a render's samples, paths per pixel, split into camera samples and children.

    s = split(Request(scene_samples=16, style_children=16, denoised=True))
    s.camera_samples, s.children, s.paths, s.note   # 4, (4,), 16, "samples=16: spp=4 x 4 children"

`samples` is what Cycles calls Samples: paths per pixel, whatever the style. A camera sample of a
style with n children costs n paths (the product over the stylized levels; a closed-form style,
with no children, one). The rule (chosen by measurement; docs/look.md):

- neither camera samples nor children given: n = min(the style's n, CHILDREN, samples) for one
  stylized level where the expectation is denoised before g (every front end's default for a style
  of several children), n = min(the style's n, samples) where it is not (g applied to each camera
  sample's mean of n children is biased by O(1/n)); several levels keep their counts;
  camera samples = max(1, round(samples / P));
- children given: camera samples = max(1, round(samples / P));
- camera samples given: n = max(1, round(samples / camera samples)) for one level where samples was
  given too, else the style's n (the render of every call before samples existed);
- both given: as given; with samples given as well they must agree (camera samples x P = samples).

P is the product of the levels' counts (an adaptive count n0:n_max counts n0). A cap on camera
samples (the expectation buffer's) lowers an auto count of camera samples and raises an auto n to
ceil(samples / camera samples); a floor (the error AOVs' variance needs 2 camera samples) raises
an auto count and lowers an auto n to max(1, round(samples / camera samples)).
`pipeline.resolve.resolve` splits every render once, after its denoising method is chosen; a
draft is a smaller request of its own (`draft_request`). Design: docs/design/sample_budget.md.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, replace

from styletrace.errors import UsageError
from styletrace.pipeline.terms import PYTHON, Terms

#: the most children an auto split gives a camera sample. Measured at equal samples (16 and 64)
#: on three interiors and exteriors: 2 to 4 children per camera sample gave the least noise between
#: seeds with the expectation denoised, 16 the most (3 to 5 dB more), at about equal time; and
#: camera samples of few children let a viewport show a clean image after its first, cheap pass
#: (docs/design/sample_budget.md)
CHILDREN = 4
#: the most camera samples an expectation buffer holds by default (512 x 512 at 16 per pixel);
#: memory is about `lookdev.buffer.bytes_per_camera_sample` times this (~270 MB for first_hit)
MAX_CAMERA_SAMPLES = 1 << 22


@dataclass(frozen=True)
class Request:
    """What a render's caller and scene said about its cost.

    Args:
        scene_samples: the scene sampler's sample count: the budget where `samples` is None.
        samples: paths per pixel, as the caller named them, or None.
        camera_samples: camera samples per pixel given (the caller's spp), or None.
        children: children per stylized level given (the caller's or the scene file's), or None.
        style_children: the style's own n (`Style.default_inner`; 0 for a closed-form style or an
            integrator without children).
        levels: the stylized levels (`stylize_depth`).
        object_children: the most children a `styled` BSDF's own style draws at the first level
            (its own count, which no split changes; 0: no styled object draws children).
        least_camera_samples: the fewest camera samples an auto count may take (2 where the error
            AOVs estimate each pixel's variance).
        denoised: the expectation is denoised before g, so an auto n is at most CHILDREN; False:
            g meets each camera sample's mean, and an auto n is the style's.
        terms: the caller's names of samples, spp and inner, for the one-line error.
    """
    scene_samples: int
    samples: int | None = None
    camera_samples: int | None = None
    children: tuple[int, ...] | None = None
    style_children: int = 0
    levels: int = 1
    object_children: int = 0
    least_camera_samples: int = 1
    denoised: bool = False
    terms: Terms = PYTHON

    @property
    def budget(self) -> int:
        """Paths per pixel to spend: the caller's samples, else the scene's."""
        return self.scene_samples if self.samples is None else int(self.samples)

    @property
    def closed(self) -> bool:
        """Whether a camera sample draws no children (one path each, whatever n says)."""
        return self.style_children == 0

    @property
    def chooses_children(self) -> bool:
        """Whether the budget may choose n: one stylized level of a style with children, none
        given."""
        return self.children is None and self.levels == 1 and not self.closed


@dataclass(frozen=True)
class Split:
    """A request's camera samples and children.

    Args:
        request: what was asked. camera_samples: camera samples per pixel. children: children per
            stylized level (one count for every level, or one per level).
    """
    request: Request
    camera_samples: int
    children: tuple[int, ...]

    @property
    def per_camera_sample(self) -> int:
        """P: paths one camera sample draws (`paths_per_camera_sample`)."""
        return paths_per_camera_sample(self.children, self.request)

    @property
    def paths(self) -> int:
        """Paths per pixel: camera samples x P."""
        return self.camera_samples * self.per_camera_sample

    @property
    def chosen(self) -> bool:
        """Whether the budget chose anything (the camera samples, or n where samples was given
        with the camera samples)."""
        r = self.request
        return r.camera_samples is None or (r.chooses_children and r.samples is not None)

    @property
    def note(self) -> str:
        """The `auto` line's words for the split ('' where the caller gave every count)."""
        if not self.chosen:
            return ""
        r = self.request
        head = f"samples={r.budget}: spp={self.camera_samples}"
        # a styled object's own count is not the split's: said, so the line is the whole cost
        own = (f" (styled objects: their own, up to {r.object_children})"
               if r.object_children else "")
        if r.closed:
            return f"{head} (no children){own}"
        if r.levels == 1:
            n = self.children[0]
            return f"{head} x {n} {'child' if n == 1 else 'children'}{own}"
        # several levels: each level's count, as --inner spells them, and what they multiply to
        counts = ",".join(str(self.children[min(k, len(self.children) - 1)])
                          for k in range(r.levels))
        return f"{head} x {counts} children ({self.paths} paths per pixel)"


def paths_per_camera_sample(children: tuple[int, ...], request: Request) -> int:
    """P: the product of the stylized levels' children counts (1 without children).

    Args:
        children: the counts, one for every level or one per level (adaptive: n0).
        request: the request (its levels, whether the style is closed-form).

    Returns:
        P >= 1.
    """
    if request.closed:
        return 1
    return math.prod(max(1, int(children[min(level, len(children) - 1)]))
                     for level in range(request.levels))


def split(request: Request, cap: int | None = None) -> Split:
    """The rule (the module doc): the camera samples and children of a request.

    Args:
        request: the budget and the counts given.
        cap: the most camera samples per pixel an auto count may take (the expectation buffer's),
            or None.

    Returns:
        The Split.

    Raises:
        UsageError: samples, camera samples and children all given and camera samples x P !=
            samples (one line, in the request's terms).
    """
    r = request
    own = (max(r.style_children, 1),)
    children = r.children if r.children is not None else own
    if r.chooses_children:
        if r.camera_samples is None:
            most = CHILDREN if r.denoised else own[0]
            children = (min(own[0], most, r.budget),)
        elif r.samples is not None:
            children = (max(1, round(r.samples / r.camera_samples)),)
    per = paths_per_camera_sample(children, r)
    if r.camera_samples is not None:
        if r.children is not None and r.samples is not None and r.camera_samples * per != r.samples:
            counts = ",".join(str(c) for c in r.children)
            t = r.terms
            raise UsageError(
                f"{t.value('samples', r.samples)} with {t.value('spp', r.camera_samples)} and "
                f"{t.value('inner', counts)} ({r.camera_samples * per} paths per pixel): give at "
                f"most two of the three"
            )
        return Split(r, r.camera_samples, children)
    spp = max(1, round(r.budget / per))
    if spp < r.least_camera_samples:
        spp = r.least_camera_samples
        if r.chooses_children:
            children = (max(1, round(r.budget / spp)),)
    if cap is not None and spp > cap:
        spp = max(1, cap)
        if r.chooses_children:
            children = (math.ceil(r.budget / spp),)
    return Split(r, spp, children)


def averages_children(request: Request) -> bool:
    """Whether a camera sample of `request` averages more than one child at its first stylized
    level when the expectation is denoised (so that denoising it before g differs from denoising
    the image after it). It is so in the split without the denoiser too: an auto n of at most 1
    is the same in both.

    Args:
        request: the request, before its denoising is chosen.

    Returns:
        True where the first level's n (n0 of an adaptive count) is above 1, the integrator's or
        a styled object's.
    """
    if request.object_children > 1:
        return True
    if request.closed:
        return False
    return int(split(replace(request, denoised=True)).children[0]) > 1


def draft_request(whole: Split) -> Request:
    """The request of a draft of a render: one camera sample of the render's children (given, so
    that `split` keeps them as they are).

    Args:
        whole: the render's split.

    Returns:
        The draft's request: its split is one camera sample of `whole.children`.
    """
    return replace(whole.request, samples=None, camera_samples=1, children=whole.children,
                   least_camera_samples=1)


__all__ = ["Request", "Split", "split", "paths_per_camera_sample", "averages_children",
           "draft_request", "CHILDREN", "MAX_CAMERA_SAMPLES"]
