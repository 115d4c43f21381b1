"""Scene-relative defaults: the styles' 'auto' parameters, resolved on the scene about to be
rendered.

    integrator, chosen = resolve_defaults(scene, integrator)   # before rendering

A style declares a parameter 'auto' (default None) with a rule (`Param.auto`);
`Style.auto_values(facts)` applies it to the `Facts` computed here per style slot: `camera`,
`brightness(qs)` (quantiles of a pilot's first-hit brightness on the slot's objects) and
`depth(qs)`. `resolve_defaults` returns the integrator with the values pinned (given values win)
and one line naming them. The pilot runs here, before Mitsuba's render call, and only if a
brightness rule is left. Rationale and the pilot's design: docs/design/scene_relative_defaults.md.
"""
from __future__ import annotations

from dataclasses import replace
from functools import cached_property
from typing import Any

import numpy as np

from styletrace.config import settings as S
from styletrace.errors import StyleError
from styletrace.gate import dr, mi
from styletrace.host_arrays import aligned
from styletrace.jit import no_collection
from styletrace.kernel.emitter_sampler import EmitterSampler
from styletrace.kernel.integrator import StylizedIntegrator
from styletrace.kernel.path import Hooks, Start, WalkConfig, exitant
from styletrace.kernel.scene_graph import SceneGraph
from styletrace.kernel.styled_bsdf import StyledBSDF
from styletrace.kernel.volume import collision_site, volume_walk
from styletrace.styles.base import Camera, Style, Vertex, camera, lanes

#: the settings the pilot's trace reads (`ScenePilot._trace`)
PILOT_SETTINGS = ("max_depth", "rr_depth", "emitter_sampling", "stylize")
#: cells of the pilot grid along the film's longer side, and camera samples per cell
PILOT_CELLS = 32
PILOT_SPP = 16
PILOT_SEED = 0x5EED


def weighted_quantiles(values: np.ndarray, weights: np.ndarray, qs) -> list[float]:
    """Quantiles of the distribution putting mass `weights` on `values` (the inverted CDF).

    Args:
        values: the values, any shape (flattened).
        weights: their weights, the same size; values of weight <= 0 are never quantiles.
        qs: the probabilities, each in [0, 1].

    Returns:
        Per q, the smallest value whose cumulative weight reaches q (as floats).
    """
    # numpy 2's np.quantile(..., weights=, method="inverted_cdf"), which numpy 1.x (still allowed
    # by pyproject) lacks; spelled out so that both give the same auto values
    v = np.asarray(values, dtype=np.float64).ravel()
    w = np.asarray(weights, dtype=np.float64).ravel()
    keep = w > 0  # a value of no weight is never a quantile, not even the 0th
    v, w = v[keep], w[keep]
    order = np.argsort(v, kind="stable")
    v, w = v[order], w[order]
    cdf = np.cumsum(w)
    cdf /= cdf[-1]
    index = np.searchsorted(cdf, np.asarray(qs, dtype=np.float64), side="left")
    return [float(x) for x in v[np.minimum(index, len(v) - 1)]]


class ScenePilot:
    """The pilot's camera samples: per sample its cell, first hit (BSDF, position, normal,
    direction, depth) and one `path` estimate of the radiance there (`samples`). Traced on first
    use, once per `resolve_defaults` (or per `pipeline.resolve`, which shares it).

    Args:
        scene: the mi.Scene to trace (its first sensor and crop).
        settings: the integrator's Settings; the trace reads PILOT_SETTINGS.
    """

    def __init__(self, scene: mi.Scene, settings: S.Settings):
        self.scene, self.settings = scene, settings

    def serves(self, scene: mi.Scene, settings: S.Settings) -> bool:
        """Whether these samples are the pilot of `scene` under `settings`.

        Args:
            scene: the scene to render; settings: the integrator's Settings.

        Returns:
            True for the same scene object and equal PILOT_SETTINGS (the style is not among them:
            a pinned copy of an integrator shares its pilot).
        """
        return self.scene is scene and all(getattr(self.settings, k) == getattr(settings, k)
                                           for k in PILOT_SETTINGS)

    @cached_property
    def records(self) -> dict[str, Any]:
        """The pilot's camera samples by field: cell, owner, colour, depth, p, n, wo (numpy, one row
        per camera sample)."""
        # traced and evaluated with no scene finalised meanwhile (jit.no_collection)
        with no_collection():
            return self._trace()

    def _trace(self) -> dict[str, Any]:
        scene = self.scene
        sensor = scene.sensors()[0]
        w, h = (int(x) for x in sensor.film().crop_size())
        cx = PILOT_CELLS if w >= h else max(1, round(PILOT_CELLS * w / h))
        cy = PILOT_CELLS if h >= w else max(1, round(PILOT_CELLS * h / w))
        n = cx * cy * PILOT_SPP
        rng = np.random.default_rng(PILOT_SEED)
        cell = np.repeat(np.arange(cx * cy), PILOT_SPP)
        ux = ((cell % cx) + rng.random(n)) / cx
        uy = ((cell // cx) + rng.random(n)) / cy
        ray, _ = sensor.sample_ray(
            mi.Float(0.0),
            mi.Float(0.5),
            mi.Point2f(aligned(ux), aligned(uy)),  # one kernel code (host_arrays)
            mi.Point2f(0.5, 0.5),
        )
        si = scene.ray_intersect(ray)
        sampler = mi.load_dict({"type": "independent"})
        sampler.seed(PILOT_SEED, n)
        # our own path kernel, not Mitsuba's `path`: its emitter choice does not depend on the order
        # Mitsuba lists the emitters in, so the auto values (and the image) are the same for the
        # same seed
        pi = scene.ray_intersect_preliminary(ray, coherent=True)
        graph = SceneGraph(scene)
        emitters = EmitterSampler(scene, self.settings.emitter_sampling)
        cfg = WalkConfig(scene, emitters, self.settings.max_depth, self.settings.rr_depth,
                         nulls=graph.has_null, media=graph.has_media)
        inside = None
        if graph.has_media:
            start = Start(pi, ray, medium=sensor.get_medium(), flight=True)
            if self.settings.stylize == "first_hit":
                L, si, inside = first_scattering_radiance(cfg, sampler, start, si)
            else:
                L = volume_walk(cfg, sampler, start, mi.Bool(True)).L
        else:
            L = exitant(cfg, sampler, Start(pi, ray), mi.Bool(True))
        cam = camera(scene)
        depth = dr.dot(si.p - mi.Point3f(*cam.position), mi.Vector3f(*cam.forward))
        # -1: missed; 0: the integrator's style; k: styled BSDF k-1
        owner = np.full(n, -1, dtype=np.int64)
        hit = np.array(si.is_valid(), dtype=bool)
        owner[hit] = 0
        # in `unique_styled` order; each styled BSDF with the pointers an intersection reports for
        # it (itself and the wrappers that hold it): one traversal of the scene
        for k, (_, pointers, _) in enumerate(graph.styled, start=1):
            for ptr in pointers:
                owner[np.array(si.bsdf() == mi.BSDFPtr(ptr), dtype=bool) & hit] = k
        if inside is not None:  # a collision in a medium takes the integrator's style
            owner[np.array(inside, dtype=bool)] = 0
        n_sh = dr.normalize(si.sh_frame.n)
        return {
            "cell": cell,
            "owner": owner,
            "colour": np.array(L, dtype=np.float64).T,
            "depth": np.array(depth, dtype=np.float64),
            "p": np.array(si.p).T,
            "n": np.array(n_sh).T,
            "wo": -lanes(ray.d, n).T,
        }


def first_scattering_radiance(cfg: WalkConfig, sampler, start: Start,
                              si: mi.SurfaceInteraction3f):
    """One radiance sample per camera ray, split where the integrator's first_hit stylizes: the walk
    to the first scattering (a surface, or a collision in a medium), then one path from there.

    Args:
        cfg, sampler: the pilot's WalkConfig and random stream. start: the camera rays' Start.
        si: the camera rays' first surface interactions.

    Returns:
        (radiance (mi.Spectrum), the interaction of the first scattering vertex (si, or
        `volume.collision_site`'s where that is in a medium), the lanes whose vertex is in a
        medium (mi.Bool)).
    """
    active = mi.Bool(True)
    w = volume_walk(cfg, sampler, start, active,
                    Hooks(stop=lambda s, d: d == 0, halt_in_medium=lambda d: d == 0))
    child = Start(w.pi, w.ray, w.depth, opaque=True, medium=w.medium, collision=w.collision)
    L = w.L + dr.select(w.halted, w.beta * volume_walk(cfg, sampler, child, w.halted).L, 0.0)
    return L, collision_site(si, w.collision, start.ray), w.collision.inside


def cell_colours(samples: dict, mask: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The pilot's mean colour per cell over some of its samples.

    Args:
        samples: the pilot's samples (`ScenePilot.records`).
        mask: bool per sample: the samples to average.

    Returns:
        (mean colour (cells, 3), samples per cell, each masked sample's index into those cells),
        over the cells that hold a masked sample.
    """
    cells, inverse, counts = np.unique(samples["cell"][mask], return_inverse=True,
                                       return_counts=True)
    colour = np.zeros((len(cells), 3))
    np.add.at(colour, inverse, samples["colour"][mask])
    colour /= counts[:, None]
    return colour, counts, inverse


def median_brightness(pilot: ScenePilot) -> float | None:
    """The firefly control's floor (`firefly_floor`): the median first-hit brightness the camera
    sees.

    Args:
        pilot: the scene's ScenePilot (traced here if not yet).

    Returns:
        The median over every object of the per-cell brightness (r+g+b)/3, cells weighted by
        their samples; None where the camera sees no surface.
    """
    mask = pilot.records["owner"] >= 0
    if not mask.any():
        return None
    colour, counts, _ = cell_colours(pilot.records, mask)
    return weighted_quantiles(colour.mean(axis=1), counts, [0.5])[0]


class Facts:
    """What a style's auto rule may read about the part of the scene it covers (module doc).

    Args:
        scene: the mi.Scene; pilot: its ScenePilot (or anything with the same `samples`).
        owner: whose objects: 0 the integrator's style, k the k-th of `unique_styled`.
        styles: styles applied before this one in a composition (`mapped`): the brightness is
            that of their output.
    """

    def __init__(self, scene: mi.Scene, pilot: ScenePilot, owner: int,
                 styles: tuple[Style, ...] = ()):
        self.scene, self.pilot, self.owner, self.styles = scene, pilot, owner, styles

    @cached_property
    def camera(self) -> Camera:
        return camera(self.scene)

    def mapped(self, style: Style) -> "Facts":
        """The facts of `style`'s output, for the next operand of a composition.

        Args:
            style: the operand applied before the next one.

        Returns:
            Facts of the same scene, pilot and owner whose brightness is after `style`.
        """
        return Facts(self.scene, self.pilot, self.owner, self.styles + (style,))

    @cached_property
    def _mine(self) -> np.ndarray:
        mask = self.pilot.records["owner"] == self.owner
        if not mask.any():  # the style covers nothing the camera sees directly: use every first hit
            mask = self.pilot.records["owner"] >= 0
        if not mask.any():
            raise NothingSeen
        return mask

    @cached_property
    def _cells(self) -> tuple[np.ndarray, np.ndarray]:
        """(brightness per cell, number of samples) over the cells with samples on the covered
        objects."""
        s, mask = self.pilot.records, self._mine
        colour, counts, inverse = cell_colours(s, mask)
        if self.styles:
            # a representative first hit per cell (the last sample of the cell) for styles that read
            # the vertex
            last = np.zeros(len(counts), dtype=np.int64)
            last[inverse] = np.arange(mask.sum())
            pick = lambda key: s[key][mask][last]  # noqa: E731
            colour = self._apply(colour, pick("p"), pick("n"), pick("wo"))
        return colour.mean(axis=1), counts

    def _apply(self, colour, p, n, wo) -> np.ndarray:
        arr = lambda a, t: t(np.ascontiguousarray(a.T, dtype=np.float32))  # noqa: E731
        cam = self.camera
        v = Vertex(p=arr(p, mi.Point3f), n=arr(n, mi.Vector3f), wo=arr(wo, mi.Vector3f),
                   view=mi.Vector3f(*cam.forward), depth=dr.zeros(mi.UInt32, len(p)))
        I = arr(colour, mi.Color3f)
        for style in self.styles:
            style.prepare(self.scene)
            I = style.apply(I, v)
        return np.array(I, dtype=np.float64).T

    def brightness(self, qs) -> list[float]:
        """Quantiles of the first-hit brightness (r+g+b)/3 on the covered objects, per cell
        weighted by its samples (all objects where the camera sees none of the covered).

        Args:
            qs: the probabilities, each in [0, 1].

        Returns:
            One brightness per q.

        Raises:
            NothingSeen: the camera sees no surface.
        """
        u, counts = self._cells
        return weighted_quantiles(u, counts, qs)

    def depth(self, qs) -> list[float]:
        """Quantiles of the camera depth (p - c) . forward of the covered objects' first hits.

        Args:
            qs: the probabilities, each in [0, 1].

        Returns:
            One depth per q, in scene units.

        Raises:
            NothingSeen: the camera sees no surface.
        """
        d = self.pilot.records["depth"][self._mine]
        return weighted_quantiles(d, np.ones_like(d), qs)


class NothingSeen(Exception):
    """The camera sees no surface: a style's brightness or depth rule has nothing to measure, so its
    auto values stay unresolved (the style's documented fallbacks; it shows on no pixel anyway)."""


def auto_values(style: Style, facts: Facts) -> dict[str, Any]:
    """The style's auto values that its parameters accept.

    Args:
        style: the style; facts: the Facts of the objects it covers.

    Returns:
        The values by parameter name; {} where the camera sees nothing, or where together they
        break a check across parameters. A value outside its parameter's range (a rule pushed
        past it by an extreme given value: u_min = 1e6 leaves no u_max above it) is left out:
        the style's unresolved fallback applies.
    """
    try:
        chosen = style.auto_values(facts)
    except NothingSeen:
        return {}
    params = {p.name: p for p in type(style).params}
    out = {}
    for key, value in chosen.items():
        try:
            params[key].parse(value)
        except StyleError:
            continue
        out[key] = value
    try:
        style.pinned(out)
    except StyleError:  # together they break a check across parameters: leave them all unresolved
        return {}
    return out


def unique_styled(scene: mi.Scene) -> list[StyledBSDF]:
    """The scene's styled BSDFs wherever they sit (inside wrappers, in instanced shapegroups).

    Args:
        scene: the mi.Scene.

    Returns:
        The StyledBSDFs in a fixed order (the pilot's owners 1, 2, ...).

    Raises:
        SceneError: styling the scene graph refuses (`kernel.scene_graph.SceneGraph`).
    """
    return [styled for styled, _, _ in SceneGraph(scene).styled]


def describe_defaults(style: Style, values: dict[str, Any]) -> str:
    """The account of a style's chosen auto values.

    Args:
        style: the style; values: its chosen values by parameter name.

    Returns:
        'name key=value ...', each value as its parameter shows it.
    """
    params = {p.name: p for p in type(style).params}
    return f"{style.name} " + " ".join(f"{k}={params[k].show(v)}" for k, v in values.items())


def resolve_defaults(scene: mi.Scene, integrator: mi.Integrator,
                     pilot: ScenePilot | None = None) -> tuple[mi.Integrator, str]:
    """Pin the auto values of an integrator's style and of the scene's `styled` BSDFs.

    Args:
        scene: the scene about to be rendered; its `styled` BSDFs are updated in place.
        integrator: the integrator to resolve (any other integrator is returned as it is).
        pilot: a `ScenePilot` of this scene to reuse (traced only if an auto value needs it), so
            that a caller that keeps the pilot's samples (the look-dev recorder) traces it once.

    Returns:
        (integrator, chosen): the integrator with values pinned, and a one-line account ('' if
        none).
    """
    if not isinstance(integrator, StylizedIntegrator):
        return integrator, ""
    if pilot is None or not pilot.serves(scene, integrator.settings):
        pilot = ScenePilot(scene, integrator.settings)
    notes = []
    if integrator.settings.firefly:
        integrator, note = pin_firefly(scene, integrator, pilot, integrator.settings.firefly)
        notes.append(note)
    if integrator.settings.stylize != "first_object_hit":
        style = integrator.settings.style
        chosen = auto_values(style, Facts(scene, pilot, 0))
        if chosen:
            # the parsed settings with only the style replaced (settings are parsed once, `settings`
            # module)
            s = integrator.settings
            pinned = replace(s, slot=replace(s.slot, style=style.pinned(chosen)))
            integrator = StylizedIntegrator(mi.Properties(), pinned,
                                            {**integrator.values, **chosen})
            notes.append(describe_defaults(style, chosen))
    integrator = _pin_groups(scene, integrator, pilot, notes)
    for k, bsdf in enumerate(unique_styled(scene), start=1):
        style = bsdf.slot.style
        chosen = auto_values(style, Facts(scene, pilot, k))
        if chosen:
            bsdf.slot = replace(bsdf.slot, style=style.pinned(chosen))
            notes.append(f"{describe_defaults(style, chosen)} (styled BSDF {bsdf.id() or k})")
    return integrator, "; ".join(n for n in notes if n)


def _pin_groups(scene, integrator, pilot, notes: list):
    """The light groups' styles with their auto values pinned as the integrator's own are (from
    the first-hit brightness of all the light: a group's own is not measured yet); `notes` gains
    the account of each."""
    groups = list(integrator.settings.light_groups)
    values = {}
    for i, g in enumerate(groups[1:], start=1):
        chosen = auto_values(g.slot.style, Facts(scene, pilot, 0))
        if chosen:
            groups[i] = replace(g, slot=replace(g.slot, style=g.slot.style.pinned(chosen)))
            values.update({f"{g.name}.{k}": v for k, v in chosen.items()})
            notes.append(f"{describe_defaults(g.slot.style, chosen)} (light group {g.name})")
    if not values:
        return integrator
    return StylizedIntegrator(mi.Properties(),
                              replace(integrator.settings, light_groups=tuple(groups)),
                              {**integrator.values, **values})


def pin_firefly(scene: mi.Scene, integrator: StylizedIntegrator, pilot: ScenePilot | None,
                k: float) -> tuple[StylizedIntegrator, str]:
    """Pin the firefly control's k and, unless given, its floor (`median_brightness`).

    Args:
        scene: the scene about to be rendered; integrator: the stylized integrator.
        pilot: the scene's ScenePilot to reuse, or None (one is made if the floor needs it).
        k: the control's multiple to pin (its own `firefly`, or another: the denoiser's).

    Returns:
        (the integrator, a new one where anything was pinned; the note naming the values chosen,
        '' if none).
    """
    s = integrator.settings
    chosen = {} if s.firefly == k else {"firefly": float(k)}
    if s.firefly_floor is None:
        pilot = pilot if pilot is not None and pilot.serves(scene, s) else ScenePilot(scene, s)
        floor = median_brightness(pilot)
        if floor is not None:
            chosen["firefly_floor"] = float(f"{max(floor, 0.0):.4g}")
    if not chosen:
        return integrator, ""
    pinned = replace(s, extra={**s.extra, **chosen})
    note = " ".join(f"{key}={value:g}" for key, value in chosen.items())
    return StylizedIntegrator(mi.Properties(), pinned, {**integrator.values, **chosen}), note


__all__ = ["resolve_defaults", "pin_firefly", "Facts", "ScenePilot", "weighted_quantiles",
           "PILOT_CELLS", "PILOT_SPP"]
