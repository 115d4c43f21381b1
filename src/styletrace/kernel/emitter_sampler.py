"""Emitter selection for next-event estimation, independent of the order Mitsuba lists the
emitters in (it changes from one load to the next): ordered by `stable_key`, what each emitter is.

Selection (`mode`): `auto` (the default), `spatial` where the scene's sampler is `owen_sobol` and
it has several emitters, else `uniform` (`auto_mode`); `uniform`, proportional to each emitter's
`sampling_weight` (1 by default), as Mitsuba; `power`, proportional to `sampling_weight` times the
emitted power Phi estimated as the mean weight of `Emitter.sample_ray` (no estimated power: never
chosen by next-event estimation, still reached by BSDF samples; unbiased); `spatial`, per shading
point by power, distance and orientation (`spatial_selection.SpatialSelection`).
`sample_direction` matches `Scene.sample_emitter_direction`; `pdf_direction` is its solid-angle
density of a direction that reached an emitter (the emitter's own density times its selection
probability: one gather, or for `spatial` one walk over the emitters from the same point).

Light portals (`portal` emitters, kernel/portal.py) emit nothing and are never chosen: every mode
chooses among the other emitters (`selectable`), and `auto` counts only those. Where the scene
has portals and an environment, a lane that chose the environment draws its direction from
`PortalGuide`'s mixture, half through the portals the point is inside of, half by the
environment's own sampling (kernel/portal_guide.py), and `pdf_direction` of an escaped direction is
that mixture's density: the same function computes both. A scene without portals runs exactly the
code it ran before they existed. Design: docs/design/emitter_order.md,
docs/design/spatial_emitter_selection.md, docs/design/portals.md.
"""
from __future__ import annotations

from styletrace.config.choices import EMITTER_DEFAULT as DEFAULT_MODE  # noqa: F401
from styletrace.config.choices import EMITTER_MODES as MODES
from styletrace.errors import SettingsError
from styletrace.gate import dr, mi
from styletrace.kernel.emitter_bounds import emitted_power, emitter_bounds
from styletrace.kernel.owen_sobol_sampler import sequenced
from styletrace.kernel.portal import is_portal, portals
from styletrace.kernel.portal_guide import PortalGuide
from styletrace.kernel.spatial_selection import SpatialSelection


def emitter_id(ptr) -> mi.UInt32:
    """The registry id of each lane's emitter (0 for none): a dense small integer per
    live emitter.

    Args:
        ptr: the lanes' emitters (mi.EmitterPtr).

    Returns:
        mi.UInt32.
    """
    return dr.reinterpret_array(mi.UInt32, ptr)


def stable_key(emitter: mi.Emitter) -> tuple:
    """What an emitter is, independent of the order it was loaded in: its description, and for an
    area light its shape's description and bounding box.

    Args:
        emitter: an emitter of the scene.

    Returns:
        A tuple of three strings.
    """
    shape = emitter.get_shape()
    if shape is None:
        return (str(emitter), "", "")
    return (str(emitter), str(shape), str(shape.bbox()))


def selection_order(emitters) -> list:
    """The emitters in the order selection uses: by `stable_key`, whatever order they came in.

    Args:
        emitters: the scene's emitters.

    Returns:
        list[mi.Emitter].
    """
    return sorted(emitters, key=stable_key)


def selectable(scene: mi.Scene) -> list:
    """The scene's emitters that next-event estimation chooses from: all but its light portals
    (`portal`, which emit nothing), in the order Mitsuba lists them.

    Args:
        scene: the scene.

    Returns:
        list[mi.Emitter].
    """
    return [e for e in scene.emitters() if not is_portal(e)]


def auto_mode(scene: mi.Scene) -> str:
    """What `auto` selects in a scene: `spatial` where its sampler is `owen_sobol` (the built-in
    scenes', Blender's) and it has several emitters (light portals not counted), else `uniform`: a
    scene that asks for independent samples keeps the selection it had before `spatial` existed.

    Args:
        scene: the scene.

    Returns:
        'spatial' or 'uniform'.
    """
    return "spatial" if sequenced(scene) and len(selectable(scene)) > 1 else "uniform"


class EmitterSampler:
    """Next-event estimation's choice of emitter in one scene (module docstring).

    Args:
        scene: the scene whose emitters are chosen from.
        mode: 'auto', 'uniform', 'power' or 'spatial' (`emitter_sampling`); None: the default
            (`auto_mode` resolves 'auto').

    Raises:
        SettingsError: an unknown mode.
    """
    def __init__(self, scene: mi.Scene, mode: str | None = None):
        mode = DEFAULT_MODE if mode is None else mode
        if mode not in MODES:
            raise SettingsError(f"emitter sampling '{mode}': expected one of {', '.join(MODES)}")
        emitters = selection_order(selectable(scene))
        if mode == "auto":
            mode = auto_mode(scene)
        self.mode = mode
        self.scene = scene
        self.keys = [stable_key(e) for e in emitters]  # the selection order, for tests and reports
        self.count = len(emitters)
        self.spatial = None
        # the environment sampled through the scene's portals (None: no portal, or nothing they
        # could guide); without one, every step below is the one before portals existed
        self.guide = None
        if not emitters:
            return
        env, found = scene.environment(), portals(scene)
        if env is not None and found:
            # in the stable order too: the portals' sums and choice do not follow Mitsuba's list
            self.guide = PortalGuide(selection_order(found), env)
        ids = [emitter_id(mi.EmitterPtr(e))[0] for e in emitters]
        weights = [e.sampling_weight() for e in emitters]
        self.table = dr.reinterpret_array(mi.EmitterPtr, mi.UInt32(ids))
        if mode == "spatial":
            self._set_up_spatial(scene, emitters, ids, weights)
            return
        if mode == "power":
            powered = [w * emitted_power(e) for w, e in zip(weights, emitters)]
            if sum(powered) > 0:
                weights = powered
        if not sum(weights) > 0:
            weights = [1.0] * len(emitters)
        total = sum(weights)
        self.distr = mi.DiscreteDistribution(mi.Float(weights))
        prob = [0.0] * (max(ids) + 1)
        for i, w in zip(ids, weights):
            prob[i] = w / total
        self.prob_by_id = mi.Float(prob)
        self.probabilities = [w / total for w in weights]  # in key order, for tests and reports

    def _set_up_spatial(self, scene: mi.Scene, emitters: list, ids: list, weights: list):
        """The `spatial` mode's state: each emitter's bounds (`bounds`, in key order, for tests and
        reports), the SpatialSelection over them, and the selection index by registry id."""
        sphere = scene.bbox().bounding_sphere()
        radius = float(sphere.radius) if float(sphere.radius) > 0 else 1.0
        self.bounds = [emitter_bounds(e, radius) for e in emitters]
        self.spatial = SpatialSelection(self.bounds, weights, radius)
        index = [0] * (max(ids) + 1)
        for k, i in enumerate(ids):
            index[i] = k
        self.index_by_id = mi.UInt32(index)
        self.probabilities = None  # they depend on the shading point

    def sample_direction(
        self, si: mi.SurfaceInteraction3f, sample: mi.Point2f, active: mi.Bool, visible: bool = True
    ):
        """A direction towards an emitter and its weight, as `Scene.sample_emitter_direction`.

        Args:
            si: the shading point. sample: a 2D uniform sample (its x picks the emitter, reused).
            active: the lanes that sample (mi.Bool).
            visible: test visibility (weight 0 where occluded); False: the caller estimates the
                transmittance (volume.py).

        Returns:
            (ds mi.DirectionSample3f, weight L_e / pdf mi.Spectrum), weight 0 where none.
        """
        if self.count == 0:
            return dr.zeros(mi.DirectionSample3f), mi.Spectrum(0.0)
        if self.spatial is None:
            index, x, pmf = self.distr.sample_reuse_pmf(sample.x, active)
        else:
            index, x, pmf = self.spatial.sample(si, sample.x, active)
            active &= pmf > 0.0
        emitter = dr.gather(mi.EmitterPtr, self.table, index, active)
        if self.guide is None:
            ds, weight = emitter.sample_direction(si, mi.Point2f(x, sample.y), active)
        else:
            sky = active & (emitter == self.guide.env_ptr)
            ds, weight = emitter.sample_direction(si, mi.Point2f(x, sample.y), active & ~sky)
            ds_sky, weight_sky = self.guide.sample(si, x, sample.y, sky)
            ds = dr.select(sky, ds_sky, ds)
            weight = dr.select(sky, weight_sky, weight)
        ds.pdf *= pmf
        weight *= dr.rcp(pmf)
        active &= ds.pdf != 0.0
        weight = dr.select(active, weight, 0.0)
        if not visible:
            return ds, weight
        occluded = self.scene.ray_test(si.spawn_ray_to(ds.p), active & (dr.max(weight) > 0.0))
        return ds, dr.select(occluded, 0.0, weight)

    def selection_probability(self, emitter, active: mi.Bool) -> mi.Float:
        """The probability with which each lane's emitter is chosen, wherever the shading point
        (`uniform` and `power`).

        Args:
            emitter: the lanes' emitters (mi.EmitterPtr; None: 0). active: the lanes asked.

        Returns:
            mi.Float.

        Raises:
            ValueError: in `spatial` mode, whose probabilities depend on the point
                (`pdf_direction` has it).
        """
        if self.spatial is not None:
            raise ValueError("spatial emitter selection has no probability without a point: "
                             "use pdf_direction")
        if self.count == 0:
            return mi.Float(0.0)
        return dr.gather(mi.Float, self.prob_by_id, emitter_id(emitter), active & (emitter != None))  # noqa: E711

    def pdf_direction(
        self, ref: mi.Interaction3f, ds: mi.DirectionSample3f, active: mi.Bool
    ) -> mi.Float:
        """Solid-angle density with which `sample_direction` from `ref` produces the direction
        of `ds`.

        Args:
            ref: the shading point. ds: a direction sample that reached an emitter.
            active: the lanes asked (mi.Bool).

        Returns:
            mi.Float.
        """
        if self.count == 0:
            return mi.Float(0.0)
        if self.spatial is None:
            return self._own_density(ref, ds, active) * self.selection_probability(
                ds.emitter, active
            )
        known = active & (ds.emitter != None)  # noqa: E711  (a Dr.Jit pointer comparison)
        index = dr.gather(mi.UInt32, self.index_by_id, emitter_id(ds.emitter), known)
        return self._own_density(ref, ds, active) * self.spatial.pmf(ref, index, known)

    def _own_density(self, ref, ds, active) -> mi.Float:
        """The density with which the emitter ds reached samples ds.d once chosen: its own, or for
        the environment of a scene with portals the mixture's (`PortalGuide.density`)."""
        if self.guide is None:
            return ds.emitter.pdf_direction(ref, ds, active)
        sky = active & (ds.emitter == self.guide.env_ptr)
        own = ds.emitter.pdf_direction(ref, ds, active & ~sky)
        return dr.select(sky, self.guide.density(ref, ds, sky), own)
