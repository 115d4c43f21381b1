"""Recording an expectation buffer while rendering: `render_buffer` and the recording integrator.

    buf = styletrace.render_buffer("cornell-box", style="cel", spp=16, inner=16, seed=0)

`RecordingIntegrator` is the `stylized` integrator that also keeps, per camera sample, the θ-free
data of `lookdev.buffer`, written by the same kernel and collected after each pass of
`pipeline.passes`; the recorded image is the render's. Refused with one line: `first_n_hits`, more
than one stylized level, `expansion_pass`, a per-sample style (acp), a film other than rgb, more
samples than the cap. See docs/design/expectation_buffer.md.
"""
from __future__ import annotations

import os
from dataclasses import replace
from typing import Any, Callable, Iterator

import numpy as np

from styletrace.config import settings as S
from styletrace.config.estimator_registry import (
    MEAN_ESTIMATORS,
    child_mean,
    firefly_cap,
    make_estimator,
)
from styletrace.errors import SceneError, SettingsError, UsageError
from styletrace.gate import dr, mi
from styletrace.host_arrays import aligned
from styletrace.images import save_safely
from styletrace.kernel.integrator import StylizedIntegrator
from styletrace.kernel.vertex import emission
from styletrace.lookdev import film_filter
from styletrace.lookdev.buffer import (
    FORMAT,
    MAX_CAMERA_SAMPLES,
    MAX_SEQUENCE_CAMERA_SAMPLES,
    PILOT,
    VERSION,
    Buffer,
    bytes_per_camera_sample,
    host_array,
)
from styletrace.lookdev.restyle import finish_slot, slot_record
from styletrace.lookdev.sequence import Recorder, budget
from styletrace.pipeline import passes as pass_loop
from styletrace.pipeline.runner import Finisher, Written
from styletrace.scene.builtin import DEFAULT
from styletrace.scene.defaults import ScenePilot, unique_styled
from styletrace.scene.loading import film_format
from styletrace.styles.base import Vertex, camera_forward


def check_recordable(settings: S.Settings, slots) -> None:
    """Refuse settings a buffer cannot record, before anything is traced.

    Args:
        settings: the integrator's parsed Settings.
        slots: its StyleSlots for the per-slot checks ([]: the settings alone).

    Raises:
        SettingsError: reuse, first_n_hits, stylize_depth != 1, an expansion pass, feature lines,
            aovs, an adaptive inner count or a per-sample style (one line each).
    """
    if settings.reuse != "off":
        raise SettingsError(
            f"reuse={settings.reuse} cannot be buffered: a buffer keeps each camera sample's own "
            f"children, reuse pools its neighbours'; use reuse=off"
        )
    if settings.stylize == "first_n_hits":
        raise SettingsError(
            "stylize=first_n_hits cannot be buffered: its styles nest (each level's children are "
            "styled again); use first_hit or first_object_hit"
        )
    if settings.stylize_depth != 1:
        raise SettingsError(
            f"bad value {settings.stylize_depth} for 'stylize_depth': a buffer holds one stylized "
            f"level (1)"
        )
    if settings.expansion_pass:
        raise SettingsError(
            f"bad value {settings.expansion_pass} for 'expansion_pass': a buffer replays each "
            "camera sample's own children, not a pre-pass's expansion point; use expansion_pass=0"
        )
    if settings.lines is not None:
        raise SettingsError(
            "feature lines (lines=true) cannot be buffered: a buffer keeps the radiance before g, "
            "not where lines replaced it; record without lines"
        )
    if settings.light_groups:
        raise SettingsError(
            f"bad value {','.join(g.name for g in settings.light_groups[1:])!r} for "
            "'light_groups': a buffer of light groups is not yet supported; record without them"
        )
    if settings.aovs:
        raise SettingsError(
            "bad value True for 'aovs': a buffer keeps the children's means, not the error AOVs; "
            "render with aovs instead"
        )
    for slot in slots:
        if S.adaptive(slot.inner):
            raise SettingsError(
                f"bad value {','.join(map(str, slot.inner))!r} for 'inner_samples': a buffer "
                f"keeps one fixed count of children per vertex; use a fixed count"
            )
        if slot.style.per_sample:
            raise SettingsError(
                f"style '{slot.style.name}' cannot be buffered: it applies g to every child "
                f"sample, a buffer keeps only their mean"
            )


def check_film(scene: mi.Scene) -> mi.Film:
    """The scene's film, where a buffer can record it.

    Args:
        scene: the mi.Scene (its first sensor's film).

    Returns:
        The mi.Film: an rgb film with any filter `film_filter.describe_filter` rebuilds, any border.

    Raises:
        SceneError: another pixel format or filter (one line).
    """
    film = scene.sensors()[0].film()
    if film_format(scene) != "rgb":
        raise SceneError(f"the film's pixel_format is '{film_format(scene)}': buffers need an rgb "
                         f"film")
    film_filter.describe_filter(film.rfilter())
    return film


def to_film(arrays: dict[str, Any], tile: pass_loop.Tile, width: int,
            height: int | None = None, border: int = 0, filtered: bool = False
            ) -> dict[str, Any]:
    """One pass's arrays with `pixel` made the film's (until here: the pass's window's).

    Args:
        arrays: the pass's arrays (numpy, or Dr.Jit where the kernel left them: `_pass_arrays`);
            `pixel` (numpy): the lane's pixel in the pass's (widened) crop window.
        tile: the pass's `pipeline.passes.Tile`; width, height: the film's crop size (height
            None: the tile's bottom edge). border: the window's widening on each side.
        filtered: a filter other than a box: every sample stays (it weighs on the pixels its filter
            covers), `own` marks those of kept pixels, a border sample's pixel is the film's
            nearest. Box: the samples of pixels the tile leaves to a neighbour go (`Tile.keep`).

    Returns:
        The pass's arrays, `pixel` a row-major index into the film's crop window; a Dr.Jit array
        stays one (the samples kept gathered on the device). A tile that is the whole film, with no
        border, keeps every array as it is (its pixels are the film's already).
    """
    tw, th = tile.size
    height = height if height is not None else tile.offset[1] + th
    rows, cols = tile.keep
    r0, r1 = rows.start or 0, th if rows.stop is None else rows.stop
    c0, c1 = cols.start or 0, tw if cols.stop is None else cols.stop
    if (border == 0 and tuple(tile.offset) == (0, 0) and (tw, th) == (width, height)
            and (r0, r1, c0, c1) == (0, th, 0, tw)):
        # the common case (one tile, box filter or no border): `pixel` is the film's as it is;
        # measured 0.5-1.7 s for 4M coverage points with the general indexing below (issue 36)
        out = dict(arrays)
        if filtered:
            out["own"] = np.ones(arrays["pixel"].shape[0], dtype=np.uint8)
        return out
    ew = np.int64(tw + 2 * border)
    local = arrays["pixel"].astype(np.int64)
    lx, ly = local % ew - border, local // ew - border
    keep = (ly >= r0) & (ly < r1) & (lx >= c0) & (lx < c1)
    if filtered:
        out = dict(arrays)
        out["own"] = keep.astype(np.uint8)
        fx = np.clip(lx + tile.offset[0], 0, width - 1)
        fy = np.clip(ly + tile.offset[1], 0, height - 1)
        out["pixel"] = (fy * width + fx).astype(np.uint32)
        return out
    out = {}
    # a sequence's events, children and uniform numbers follow their camera sample
    if "seq_count" in arrays:
        counts = host_array("seq_count", arrays["seq_count"])
        events = np.repeat(keep, counts.astype(np.int64))
        kinds = host_array("seq_kind", arrays["seq_kind"])
        out.update(
            seq_count=counts[keep],
            seq_kind=kinds[events],
            child=host_array("child", arrays["child"])[:, events[kinds == 1]],
            uniform=host_array("uniform", arrays["uniform"])[events[kinds == 0]],
        )
    index = None
    for k, a in arrays.items():
        if k in out:
            continue
        if isinstance(a, np.ndarray):
            out[k] = a[..., keep]
        else:  # on the device: gathered there
            if index is None:
                index = mi.UInt32(aligned(np.flatnonzero(keep), np.uint32))
            out[k] = dr.gather(type(a), a, index)
    fx, fy = lx[keep] + tile.offset[0], ly[keep] + tile.offset[1]
    out["pixel"] = (fy * width + fx).astype(np.uint32)
    return out


def _window(tile: pass_loop.Tile) -> dict:
    """A tile as the header's `layout` keeps it: crop window offset and size, rows and columns
    kept."""
    (tw, th), (rows, cols) = tile.size, tile.keep
    return {"offset": list(tile.offset), "size": list(tile.size),
            "keep": [rows.start or 0, th if rows.stop is None else rows.stop,
                     cols.start or 0, tw if cols.stop is None else cols.stop]}


def inputs(slot):
    """`slot` with its style's real parameters as kernel inputs (`Style.opaque`) where its
    estimator is direct application: a new value (a restyle's, or auto values an edit moved)
    reuses the compiled kernel, and a restyle evaluates g as the recording did. Other estimators
    build their forms from the values on the host: as they are.

    Args:
        slot: a StyleSlot.

    Returns:
        The StyleSlot.
    """
    if slot.estimator != "direct":
        return slot
    return replace(slot, style=slot.style.opaque())


class RecordingIntegrator(StylizedIntegrator):
    """`stylized`, plus the per-lane data of an expectation buffer in `self.kept` after each
    `sample()`.

    Args:
        base: the StylizedIntegrator to record (its settings and values: auto values pinned).
        sequence: keep each camera sample's children and uniforms in call order (an unbiased
            estimator); False: the children's mean.
        per_sample: the sequence recorder's places per camera sample (`sequence.budget`).
    """

    def __init__(self, base: StylizedIntegrator, sequence: bool = False, per_sample: int = 0):
        super().__init__(mi.Properties(), base.settings, base.values)
        self.kept: dict[str, Any] = {}
        #: keep each camera sample's sequence of children and uniforms (else the children's mean)
        self.sequence, self.per_sample = sequence, per_sample
        self.recorder: Recorder | None = None

    def sample(self, scene, sampler, ray, medium=None, active=True):
        self.kept = {}
        if self.sequence:
            self.recorder = Recorder(dr.width(ray.d), self.per_sample)
        spec, valid, aovs = super().sample(scene, sampler, ray, medium, active)
        kept = self.kept
        # no stylized vertex traced at all (first_object_hit without styled objects)
        if "slot" not in kept:
            width = dr.width(ray.d)
            zero = dr.zeros(mi.Vector3f, width)
            kept.update(
                p=zero,
                n=zero,
                wo=zero,
                mean=mi.Color3f(zero),
                depth=dr.zeros(mi.UInt32, width),
                slot=dr.full(mi.Int32, -1, width),
                L_before=mi.Color3f(spec),
                beta=mi.Color3f(zero),
            )
        if self.settings.stylize == "first_hit":
            # the environment where nothing was hit
            kept["L_before"] = dr.select(kept["slot"] >= 0, 0.0, spec)
        dr.schedule(*kept.values())  # evaluated by the same kernel as the image
        return spec, valid, aovs

    def stylized(self, level, sampler, site, active):
        si = site.si
        v = Vertex(p=si.p, n=mi.Vector3f(si.sh_frame.n), wo=-site.ray.d,
                   view=mi.Vector3f(self.view), depth=mi.UInt32(site.depth))
        styled = self.styled_mask(si) if len(self.targets) > 1 else mi.Bool(False)
        total, slot, mean = mi.Spectrum(0.0), mi.Int32(-1), mi.Color3f(0.0)
        for i, target in enumerate(self.targets):
            here = active & (_any(si.bsdf(), target.bsdfs) if target.bsdfs else ~styled)
            if self.sequence:
                value = self.estimate(target.slot, level, sampler, site, here, v)
            else:
                m = self._mean(target.slot, level, sampler, site, here)
                value = self.finish_mean(target.slot, m, v)
                mean = dr.select(here, m, mean)
            total = dr.select(here, value, total)
            slot = dr.select(here, i, slot)
        self.kept.update(p=mi.Vector3f(v.p), n=v.n, wo=v.wo, depth=v.depth, slot=slot, mean=mean)
        return total

    def finish_mean(self, slot, m, v):
        """The slot's estimate from the children's mean (`restyle.finish_slot`;
        `denoise.coverage` overrides it).

        Args:
            slot: the StyleSlot; m: mi.Color3f, the children's mean per lane; v: the Vertex.

        Returns:
            mi.Color3f, the estimate per lane.
        """
        return finish_slot(inputs(slot), m, v)

    def through(self, w, value):
        self.kept.update(L_before=mi.Color3f(w.L), beta=dr.select(w.halted, w.beta, 0.0))
        return super().through(w, value)

    def estimate(self, slot, level, sampler, site, active, v) -> mi.Spectrum:
        """`StylizedIntegrator.estimate` with every draw and uniform also noted in the recorder's
        pool. The same calls on the same stream in the same order: the estimate is the render's."""
        if not self.sequence:
            return super().estimate(slot, level, sampler, site, active, v)
        style, rec = slot.style, self.recorder
        if style.closed_form:
            return style.apply(mi.Color3f(0.0), v)

        def draw(carry):
            smp, count, ucount = carry
            x = self.child(level, smp, site, active)
            count = rec.child(count, x)
            if style.per_sample:
                x = style.apply(x, v)
            return x, (smp, count, ucount)

        def uniform(carry):
            smp, count, ucount = carry
            u = smp.next_1d()
            return u, (smp, *rec.uniform(count, ucount, u))

        value, (_, rec.count, rec.ucount) = make_estimator(slot, level, v).run(
            draw, (sampler, rec.count, rec.ucount), uniform, active, like=mi.Color3f)
        return value

    def _mean(self, slot, level, sampler, site, active) -> mi.Color3f:
        """The mean of the slot's n children: the same draws, in the same order, and the same
        firefly control as the `direct` estimator."""
        if slot.style.closed_form:
            return mi.Color3f(0.0)

        def draw(carry):
            (smp,) = carry
            return self.child(level, smp, site, active), (smp,)

        def uniform(carry):
            (smp,) = carry
            return smp.next_1d(), (smp,)

        scene = self.walk_config.scene
        emitted = emission(scene, site.si, active) if firefly_cap(self.settings) else None
        value, _ = child_mean(slot, level, self.settings, emitted).run(draw, (sampler,), uniform,
                                                                       active, like=mi.Color3f)
        return value


def _any(ptr, bsdfs) -> mi.Bool:
    mask = mi.Bool(False)
    for b in bsdfs:
        mask |= ptr == mi.BSDFPtr(b)
    return mask


def sensor_description(sensor) -> dict:
    """What a restyle needs to rebuild the camera (`restyle.camera_scene`).

    Args:
        sensor: the mi.Sensor.

    Returns:
        {"kind": "perspective" or "orthographic", "x_fov" (None if orthographic), "size",
        "crop_size", "crop_offset"}: JSON-able.
    """
    params = mi.traverse(sensor)
    film = sensor.film()
    return {"kind": "perspective" if "x_fov" in params else "orthographic",
            "x_fov": float(params["x_fov"][0]) if "x_fov" in params else None,
            "size": [int(v) for v in film.size()], "crop_size": [int(v) for v in film.crop_size()],
            "crop_offset": [int(v) for v in film.crop_offset()]}


def _slots(integrator: StylizedIntegrator, scene: mi.Scene) -> list[dict]:
    targets = integrator.targets_for(scene)
    return [
        slot_record(
            t.slot, "object" if t.bsdfs else "integrator", t.bsdfs[0].id() if t.bsdfs else ""
        )
        for t in targets
    ]


def _pass_arrays(kept: dict, spp: int, stylize: str,
                 recorder: Recorder | None) -> dict[str, Any]:
    """One pass's kept arrays: Dr.Jit arrays where the kernel wrote them (copied to the host only
    when read, `buffer.Arrays`), `pixel` (numpy) the lane's pixel in the pass's (widened) crop
    window."""
    dr.eval(*kept.values())  # a no-op after the pass: its kernel wrote them (`sample`)
    width = dr.width(kept["slot"])
    out = {"pixel": np.arange(width, dtype=np.uint32) // np.uint32(spp),
           "slot": mi.Int32(kept["slot"])}
    if "pos" in kept:  # placed by the recording integrator itself (`denoise.coverage`)
        out["pos"] = mi.Point2f(kept["pos"])
    for k in ("p", "n", "wo", "L_before") + (() if recorder else ("mean",)):
        out[k] = kept[k]
    if recorder is not None:
        out.update(recorder.collect())
    if stylize == "first_object_hit":
        out["beta"] = kept["beta"]
        out["depth"] = mi.UInt32(aligned(kept["depth"], np.uint32))
    return out


def record(
    shot: pass_loop.Shot,
    split: pass_loop.PassSplit = pass_loop.PassSplit(),
    label: str = "",
    max_camera_samples: int = MAX_CAMERA_SAMPLES,
    pilot: ScenePilot | None = None,
    recorder: Callable[..., RecordingIntegrator] | None = None,
) -> Iterator[tuple[pass_loop.Progress, Buffer]]:
    """Render like `pipeline.passes`, yielding (progress, buffer so far) after each pass.

    Args:
        shot: what to render (a `stylized` integrator), its spp and seed. split: the pass split.
        label: how the buffer names its scene; max_camera_samples: the cap on its camera samples
            (MAX_CAMERA_SAMPLES, the default, means MAX_SEQUENCE_CAMERA_SAMPLES for a sequence
            buffer).
        pilot: the ScenePilot the caller resolved auto values with (`pipeline.resolve`), or None.
        recorder: makes the recording integrator of (integrator, sequence, per_sample) (default
            RecordingIntegrator; `denoise.coverage`'s places its own camera rays).

    Raises:
        SceneError, SettingsError, UsageError: what a buffer cannot record (one line).
    """
    scene, integrator, spp, seed = shot.scene, shot.integrator, shot.spp, shot.seed
    film = check_film(scene)
    if pilot is None or not pilot.serves(scene, integrator.settings):
        pilot = ScenePilot(scene, integrator.settings)
    # pin the scene-relative defaults on the integrator, not on the recording wrapper below: a copy
    # would lose the recording; with the pilot stored below (traced here if an auto value needs it):
    # a pilot the caller resolved with is traced once for both
    integrator = pass_loop.pin_auto_values(scene, integrator, pilot)[0]
    slots = [t.slot for t in integrator.targets_for(scene)]
    check_recordable(integrator.settings, slots)
    sequence = any(s.estimator not in MEAN_ESTIMATORS for s in slots)
    per_sample = budget(slots) if sequence else 0
    rec = (recorder or RecordingIntegrator)(integrator, sequence, per_sample)
    size = film.crop_size()
    w, h = int(size[0]), int(size[1])
    spec = film_filter.describe_filter(film.rfilter())
    filtered = not film_filter.is_box(spec)
    border = int(film.rfilter().border_size()) if film.sample_border() and filtered else 0
    layout = pass_loop.tiles(w, h)
    tw, th = layout[0].size
    total = len(layout) * (tw + 2 * border) * (th + 2 * border) * spp if filtered else w * h * spp
    if sequence and max_camera_samples == MAX_CAMERA_SAMPLES:
        max_camera_samples = MAX_SEQUENCE_CAMERA_SAMPLES
    if total > max_camera_samples:
        per = bytes_per_camera_sample(rec.settings.stylize, filtered=filtered)
        what = (f"~{max_camera_samples * per / 2**20:.0f} MiB" if not sequence else
                f"the children and uniforms of the '{slots[0].estimator}' estimator take up to "
                f"{4 + per_sample * 18} bytes each")
        raise UsageError(
            f"a buffer of {w}x{h} at {spp} spp holds {total} camera samples, over the cap of "
            f"{max_camera_samples} ({what}); lower spp or the image size"
        )
    sensor = scene.sensors()[0]
    header = {
        "format": FORMAT,
        "version": VERSION,
        "scene": label,
        "width": w,
        "height": h,
        "crop_offset": [int(c) for c in film.crop_offset()],
        "filter": spec if filtered else "box",
        "seed": int(seed),
        "stylize": rec.settings.stylize,
        "max_depth": rec.settings.max_depth,
        "rr_depth": rec.settings.rr_depth,
        "slots": _slots(rec, scene),
        "stores": "sequence" if sequence else "mean",
        "events_per_sample": per_sample,
        "view": list(camera_forward(scene)),
        "sensor_to_world": np.array(sensor.world_transform().matrix, dtype=np.float64)
        .reshape(4, 4, -1)[..., 0]
        .tolist(),
        "sensor": sensor_description(sensor),
        "passes": [],
    }
    if filtered:
        header.update(sample_border=bool(border), layout=[_window(t) for t in layout])
    # the scene-defaults pilot, kept so that a restyle resolves 'auto' style values as a render of
    # the scene would
    # the one trace of the pilot: resolve's, or here if no auto value needed it
    pilot = pilot.records
    owners = {id(b): k for k, b in enumerate(unique_styled(scene), start=1)}
    for rec_slot, target in zip(header["slots"], rec.targets_for(scene)):
        rec_slot["pilot_owner"] = owners.get(id(target.bsdfs[0]), 0) if target.bsdfs else 0
        # the values the pilot chose: a restyle that changes the slot's parameters chooses them
        # again
        rec_slot["auto"] = list(getattr(target.slot.style, "chosen", ()))
    buf = Buffer(header, {PILOT + k: np.ascontiguousarray(v) for k, v in pilot.items()})
    for index, prog in enumerate(pass_loop.run_passes(replace(shot, integrator=rec), split,
                                                      pinned=True)):
        arrays = _pass_arrays(rec.kept, prog.pass_spp, rec.settings.stylize, rec.recorder)
        if filtered and "pos" not in arrays:  # where Mitsuba put each sample
            seed_i = pass_loop.pass_seed(seed, index)
            arrays["pos"] = film_filter.positions(sensor, prog.pass_spp, seed_i, device=True,
                                                  sequence=pass_loop.unit_sequence(seed, prog.unit))
        tiled = len(prog.layout) > 1  # the crop windows `pipeline.passes` renders, one per pass
        if tiled:
            buf.header["tiles"] = len(prog.layout)
        arrays = to_film(arrays, prog.layout[prog.tile], w, h, border, filtered)
        buf.append(arrays, prog.pass_spp, pass_loop.pass_seed(seed, index),
                   prog.tile if tiled else None)
        rec.kept, rec.recorder = {}, None
        yield prog, buf


def scene_label(scene: Any) -> str:
    """How the buffer names its scene (the equivalent command line uses it).

    Args:
        scene: the scene as the caller gave it: None, a name or path, a dict or an mi.Scene.

    Returns:
        DEFAULT for None, the name or path as a str, else "<TypeName>".
    """
    if scene is None:
        return DEFAULT
    if isinstance(scene, (str, os.PathLike)):
        return os.fspath(scene)
    return f"<{type(scene).__name__}>"


def render_buffer(scene: Any = None, *,
                  callback: Callable[[pass_loop.Progress], None] | None = None,
                  max_camera_samples: int = MAX_CAMERA_SAMPLES, **keywords: Any) -> Buffer:
    """Render as `styletrace.render` does, undenoised, and return the expectation buffer of every
    camera sample.

    The render is the pipeline's (`pipeline.resolve`: the scene's integrator settings merged, auto
    values pinned); `buffer.image` is `styletrace.render(..., denoise="off")`'s image for the same
    pass split.

    Args:
        scene: as `styletrace.render`'s. callback: called with each Progress.
        max_camera_samples: the cap on the buffer's camera samples (`record`).
        **keywords: `styletrace.render`'s keywords but the denoising ones (the Job is
            `pipeline.job.python_job`'s).

    Raises:
        StyletraceError: what `styletrace.render` refuses, and what a buffer cannot record.
    """
    from styletrace.pipeline.execute import InProcess
    from styletrace.pipeline.job import python_job
    from styletrace.pipeline.resolve import resolve
    from styletrace.pipeline.runner import Runner
    r = resolve(python_job(scene, max_camera_samples=max_camera_samples, **keywords))
    recorded = Recorded(label=scene_label(scene), max_camera_samples=max_camera_samples)
    return Runner(r, InProcess(), recorded).result(callback)


class Recorded(Finisher):
    """A run's finisher that records the expectation buffer of every finished pass (`record`)
    beside the image: the command line's `--buffer FILE`, Blender's Record buffer.

    Args:
        path: the .npz file the buffer is written to beside the image, or None (not written).
        label: how the buffer names its scene ('': `scene_label` of the job's scene).
        keep: called with the buffer after the passes (Blender), or None.
        max_camera_samples: the cap on camera samples (`record`).
    """
    local = "--buffer renders locally: the buffer is recorded in this process (no --ray)"

    def __init__(self, path: str | None = None, label: str = "",
                 keep: Callable[[Buffer], None] | None = None,
                 max_camera_samples: int = MAX_CAMERA_SAMPLES):
        self.buffer, self.label, self.keep = path, label, keep
        self.max_camera_samples = max_camera_samples
        self.recorded: Buffer | None = None

    def check(self, resolved, executor) -> None:
        check_recordable(resolved.integrator.settings, [])  # before the runner's generic checks
        self.label = self.label or scene_label(resolved.job.scene)
        if self.buffer is not None:
            from styletrace.lookdev.buffer import check_buffer_path
            check_buffer_path(self.buffer)

    def source(self, resolved, executor, lock) -> Iterator[pass_loop.Progress]:
        from styletrace.pipeline.execute import shot_of, split_of
        for prog, buf in record(shot_of(resolved), split_of(resolved), self.label,
                                self.max_camera_samples, resolved.pilot):
            buf.image = prog.image
            self.recorded = buf
            yield prog
        if self.keep is not None:
            self.keep(self.recorded)

    def result(self, prog) -> Buffer:
        return self.recorded

    def write(self, prog, output: str, pixel_format: str) -> Written:
        out = save_safely(prog.image, output, pixel_format, self.channels(None))
        buf = self.recorded
        buf.save(self.buffer)
        return Written(out, (self.buffer,), prog.image,
                       f"; {buf.camera_samples} camera samples, {buf.nbytes / 2**20:.1f} MiB")


__all__ = ["RecordingIntegrator", "record", "render_buffer", "Recorded", "check_recordable",
           "check_film", "to_film"]
