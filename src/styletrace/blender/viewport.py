"""Rendered shading in the 3D viewport: the model, one progressive schedule per view, fed by
`viewport_sync`. Blender's hooks that draw it are `viewport_hooks`'.

    vp = Viewport()
    vp.update(depsgraph, settings)                     # view_update: sync what changed
    vp.set_view(view_matrix, window_matrix, w, h)      # view_draw: the region's camera
    image, label = vp.session.latest()                 # the newest image, drawn with `gpu`

A `ViewportSession` is a thin adapter around the one progressive schedule
(`progressive.schedule.Schedule`, the browser preview's too): its first step traces the view's
surfaces at the draft's size and, after a camera move, shows the image of the view before carried
to the new one (`viewport_carry`); its draft (`Job.draft` at
`rules.draft_size`), then F12's job (`f12.job`: the same samples, seed, pass split and Denoise,
`denoise.finishers.plan`), its previews and final image, then the warm-up of the restyle kernels.
The session shows each frame, restyled where the style changed since the passes started. A style
change restyles the recorded buffer; any other change starts a new session on the kept Mitsuba
objects. Every session's Dr.Jit work runs under one lock, `TURNS`. Design: docs/design/viewport.md.
"""
from __future__ import annotations

import gc
import threading
import time
from types import SimpleNamespace
from typing import Callable

import numpy as np

from styletrace.blender import f12
from styletrace.blender.properties import settings_integrator_values, style_values
from styletrace.blender.viewport_carry import Surfaces, carried, surfaces
from styletrace.blender.viewport_sync import SceneSync, changes_of, view_sensor
from styletrace.config.choices import SAMPLER_DEFAULT
from styletrace.denoise.finishers import Expectation, Recording, plan
from styletrace.errors import StyletraceError
from styletrace.frontends import api
from styletrace.gate import dr, mi
from styletrace.lookdev.record import Recorded
from styletrace.lookdev.restyle import restyle as lookdev_restyle
from styletrace.lookdev.restyle import slots_for
from styletrace.lookdev.slider import quick_restyle
from styletrace.pipeline.denoising import Denoising
from styletrace.progressive.rules import DRAFT_QUALITY, draft_size
from styletrace.progressive.schedule import Frame, Schedule, Turns

#: seconds without a new style value after which a drag is at rest: the whole buffer is restyled
REST_S = 0.25
#: one Dr.Jit user at a time: sessions replaced by a newer one finish their step under it
TURNS = Turns()
#: the render settings that are not the style's: a change starts new passes
PASS_KEYS = ("samples", "spp", "seed", "pass_spp")
DENOISE_KEYS = ("denoise", "denoise_quality", "denoise_footprint")
#: settings whose change starts new passes, strings (the sampler type)
SAMPLER_KEYS = ("sampler",)


def snapshot(settings) -> dict:
    """The settings the viewport renders with, read on Blender's main thread.

    Args:
        settings: the scene's styletrace settings (a SceneSettings, `scene.styletrace`).

    Returns:
        `style` (the style slot's values, `style_values`), `integrator` (the `stylized`
        integrator's), `samples`, `spp` (0: auto), `seed`, `pass_spp` (ints), `denoise`,
        `denoise_quality`, `denoise_footprint`, `sampler` (strings).
    """
    return {"style": style_values(settings), "integrator": settings_integrator_values(settings),
            **{k: int(getattr(settings, k)) for k in PASS_KEYS},
            **{k: str(getattr(settings, k)) for k in DENOISE_KEYS + SAMPLER_KEYS}}


def load_view_scene(description: dict):
    """The loaded scene (`api.load_scene`) with its camera's transform opaque to Dr.Jit, so that a
    moved camera renders with the kernels already compiled (docs/design/viewport.md).

    Args:
        description: the scene dict (`SceneSync.scene_dict`), its sensor under the key "sensor".

    Returns:
        The `mi.Scene`.

    Raises:
        SceneError: a scene `api.load_scene` refuses (let through).
    """
    sc = api.load_scene(description)
    params = mi.traverse(sc)
    dr.make_opaque(params["sensor.to_world"])
    params.update()
    return sc


class ViewportSession:
    """A view's progressive render: the one schedule (`progressive.schedule.Schedule`) in a worker
    thread, its frames shown (restyled where the style changed). `latest()` is the newest image;
    `version` counts images.

    Args:
        scene_dict: a callable (width, height) -> the Mitsuba scene dict (`SceneSync.scene_dict`).
        size: the view's (width, height) in pixels.
        values: `snapshot` of the settings.
        on_image: called (in the worker) after each new image; None: nothing is called.
        draft: render the draft first.
        clock: the schedule's clock (`progressive.schedule.Schedule`; default time.perf_counter).
        before: the session of the view before a camera move, whose image this one shows carried
            to its view until its draft (`carry`); None: nothing is carried.

    `schedule`: the schedule (its `stats`: `draft_s`, `first_s`, `final_s`, `pass_s`, `denoise_s`);
    `error`: a refusal's line (None without one); `surfaces`: what the view's pixels see at the
    draft's size (`viewport_carry.Surfaces`, after the first step; None where it was skipped or
    the camera has no pixel map); `carry_s`: seconds from the start to the carried image, `kept`:
    where it was carried, not filled (H x W bool), both None without one."""

    def __init__(self, scene_dict: Callable[[int, int], dict], size: tuple[int, int],
                 values: dict, on_image: Callable[[], None] | None = None, draft: bool = True,
                 clock: Callable[[], float] = time.perf_counter,
                 before: "ViewportSession | None" = None):
        self.scene_dict, self.size, self.values = scene_dict, tuple(size), values
        self.on_image = on_image or (lambda: None)
        self.image: np.ndarray | None = None
        self.label = ""
        self.version = 0
        self.buffer = None
        self.recorded = False  # the passes record a buffer (restyles need no new pass)
        self.style: dict | None = None  # a restyled style: later frames are shown restyled
        self.before = before
        self.surfaces: Surfaces | None = None
        self.carry_s: float | None = None
        self.kept: np.ndarray | None = None
        self._draft_scene = None  # the first step's scene, which the draft renders
        self._lock = threading.Lock()
        self.schedule = Schedule(self.plan, self.plan_draft if draft else None, clock=clock,
                                 turns=TURNS, on_frame=self._on_frame, warm=self._warm,
                                 first=self.carry)

    # ---- the schedule's view ------------------------------------------------------------------

    @property
    def stats(self) -> dict:
        return self.schedule.stats

    @property
    def error(self) -> str | None:
        return self.schedule.error

    @property
    def spp_done(self) -> int:
        return self.schedule.spp_done

    @property
    def passes_run(self) -> int:
        """Passes traced (the draft's included)."""
        s = self.schedule.stats
        return len(s["pass_s"]) + (s["draft_s"] is not None)

    @property
    def done(self) -> bool:
        """Whether the schedule ran out of steps and its worker, where started, has ended."""
        return self.schedule.done

    def start(self) -> "ViewportSession":
        """Start the worker: the schedule's steps, then the garbage of this session and those
        before it (scenes, buffers, kernels' arrays) collected in the same thread, while the view
        is idle, not in the next session's draft (cel on the interior at 512 x 512, sessions in a
        row: drafts 0.54, 0.78, 0.90 s after an edit without; 0.22 to 0.35 s in 11 of 12 with).

        Returns:
            This session.
        """
        self.schedule.start("styletrace-viewport", then=gc.collect)
        return self

    def stop(self, wait: float = 0.0) -> None:
        """Ask the worker to stop after its step under way.

        Args:
            wait: seconds to wait at most for the worker to end; 0 returns at once.
        """
        self.schedule.stop(wait)

    def join(self, timeout: float | None = None) -> None:
        """Wait for the worker to end (None: until it does)."""
        self.schedule.join(timeout)

    def latest(self) -> tuple[np.ndarray | None, str]:
        """The newest image (H x W x 3 float32; None before the first) and its label."""
        with self._lock:
            return self.image, self.label

    def _show(self, image: np.ndarray, label: str) -> None:
        with self._lock:
            self.image, self.label = np.array(image, dtype=np.float32), label
            self.version += 1
        self.on_image()

    # ---- the jobs -----------------------------------------------------------------------------

    def _job(self, sc):
        """F12's job of the settings on the loaded scene `sc` (no error AOVs)."""
        v = self.values
        integ = api.make_integrator_from({**v["integrator"], "aovs": False})
        settings = SimpleNamespace(**{k: v[k] for k in (*PASS_KEYS, *DENOISE_KEYS)})
        # the viewport's passes stay even: its schedule shows and counts them
        return f12.job(sc, integ, settings, grow=False)

    def carry(self) -> None:
        """The first step (under the schedule's lock): load the scene at the draft's size (the
        draft renders it), trace its surfaces (`viewport_carry.surfaces`: one camera ray per
        pixel) and, where a session before this one has an image and surfaces of the same size,
        show that image carried to this view (`viewport_carry.carried`: pixels the view before did
        not see are filled from the nearest carried ones), labelled "reprojected". Skipped where
        the session was stopped before it ran (a newer view replaced it): that newer session then
        carries from the session before this one."""
        if self.schedule.stopped:
            return
        w, h = draft_size(*self.size)
        sc = self._draft_scene = load_view_scene(self.scene_dict(w, h))
        source = self.before
        # a session replaced before its first step has no surfaces: carry from the one before it
        while source is not None and (source.surfaces is None or source.latest()[0] is None):
            source = source.before
        self.before = None  # the chain of replaced sessions is let go
        try:
            self.surfaces, view = surfaces(sc, None if source is None else source.surfaces)
        except StyletraceError:  # a camera no pixel map projects: nothing to carry, ever
            return
        if view is None:
            return
        image, kept = carried(source.latest()[0], source.surfaces, view)
        self.kept = kept
        self.carry_s = self.schedule.clock() - self.schedule.started
        self._show(image, f"reprojected ({w}x{h})")

    def plan_draft(self):
        """The draft's run: one camera sample of the render's children at the draft's size,
        denoised as auto would, whatever Denoise says (a glimpse, not F12's image)."""
        w, h = draft_size(*self.size)
        sc, self._draft_scene = self._draft_scene, None
        if sc is None:
            sc = load_view_scene(self.scene_dict(w, h))
        job = self._job(sc)
        job = job.with_(draft=True, denoising=Denoising(
            "auto", quality=DRAFT_QUALITY, footprint=job.denoising.footprint))
        return plan(job, scene=sc, recording=Recording(label="<draft>"))

    def plan(self):
        """F12's run of the settings, recording the buffer to restyle where it can: the passes'
        (Denoise off) or the denoised one (expectation); over the buffer's cap, or for a render it
        cannot record, unrecorded (a style change then traces new passes)."""
        self._draft_scene = None  # a session without a draft: the first step's scene is done
        sc = load_view_scene(self.scene_dict(*self.size))
        job = self._job(sc)
        try:
            runner = plan(job, scene=sc, recording=Recording(label="<viewport>", keep=self._keep))
            w, h = runner.resolved.size
            if not isinstance(runner.finisher, Recorded) or w * h * runner.resolved.spp <= job.cap:
                self.recorded = isinstance(runner.finisher, (Recorded, Expectation))
                return runner
        except StyletraceError:  # not recordable (e.g. its estimator): refused again below
            pass
        self.recorded = False
        return plan(job, scene=sc, recording=Recording(label="<viewport>"))

    def _keep(self, buf) -> None:
        self.buffer = buf

    # ---- frames and restyles ------------------------------------------------------------------

    def _on_frame(self, frame: Frame) -> None:
        """Show a frame of the schedule (under its lock), restyled with a style changed since the
        passes started."""
        if frame.kind != "draft" and self.recorded and frame.buffer is not None:
            self.buffer = frame.buffer  # a preview's buffer restyles until the next replaces it
        image = frame.image
        if frame.kind != "draft" and self.style is not None and self.buffer is not None:
            image = _restyled(self.buffer, self.style)
        self._show(image, frame.label)

    def _warm(self) -> None:
        """Trace and compile the restyles of the final buffer before the first drag needs them
        (under the schedule's lock): the quick one's one-point-per-pixel view and kernel
        (`lookdev.slider`), and the whole buffer's kernel, for the current style (θ is a kernel
        input: later values reuse them)."""
        if not self.recorded or self.buffer is None:
            return
        try:  # the quick restyle's view and kernel, and the whole buffer's kernel
            _restyled(self.buffer, self.style or self.values["style"], quick=True)
            _restyled(self.buffer, self.style or self.values["style"])
        except StyletraceError:
            pass  # a buffer the quick restyle does not take: drags restyle in full

    def restyle(self, style: dict, quick: bool = False) -> float | None:
        """Show the recorded buffer restyled with `style`, with no new pass; later images are
        shown restyled too.

        Args:
            style: the style slot's values (`style_values`: "style", its parameters and optional
                "inner_samples", "estimator").
            quick: restyle one point per pixel with θ as kernel inputs (`lookdev.slider`: a
                slider being dragged); else the whole buffer (the look at rest).

        Returns:
            The seconds taken; 0.0 where a step of a schedule holds Dr.Jit (`TURNS`): the style is
            then kept and the worker shows its next image with it, without waiting here; None
            where there is no buffer to restyle yet or it cannot take the style (then the caller
            starts new passes)."""
        buf = self.buffer
        if buf is None or not restylable(buf, style):
            return None
        if not TURNS.acquire(wait=not quick):
            self.style = style  # Blender's UI thread does not wait for a pass
            return 0.0
        try:
            start = time.perf_counter()
            try:
                image = _restyled(self.buffer, style, quick=quick)
            except StyletraceError:
                return None
            self.style = style
            seconds = time.perf_counter() - start
        finally:
            TURNS.release()
        how = "restyled at one point per pixel" if quick else "restyled"
        self._show(image, f"{how}, {self.spp_done} spp")
        return seconds


def _rest(values: dict) -> dict:
    """The integrator's values that are not the style slot's."""
    return {k: v for k, v in values["integrator"].items() if k not in values["style"]}


def _restyled(buf, style: dict, quick: bool = False) -> np.ndarray:
    """`buf` restyled with the style slot's values `style` (`quick`: `lookdev.slider`'s)."""
    values = dict(style)
    how = quick_restyle if quick else lookdev_restyle
    return how(buf, style=values.pop("style"), inner=values.pop("inner_samples", None),
               estimator=values.pop("estimator", None), **values)


def restylable(buf, style: dict) -> bool:
    """Whether `buf` can take the style slot's values `style` without a new pass (host only: no
    Dr.Jit, so it needs no lock).

    Args:
        buf: a recorded buffer. style: the style slot's values (`style_values`).

    Returns:
        False where `lookdev.restyle.slots_for` refuses the change (another n, a per-sample
        style, an estimator a buffer of means cannot replay, a bad value).
    """
    values = dict(style)
    try:
        slots_for(buf, style=values.pop("style"), inner=values.pop("inner_samples", None),
                  estimator=values.pop("estimator", None), **values)
    except StyletraceError:
        return False
    return True


class Viewport:
    """One 3D view's state: the synced scene, its camera, the session rendering it.

    Args:
        on_image: called in the session's worker after each new image; None: nothing is called.
        draft: each session renders a draft first.
        warn: takes the export's warnings, one line each (default: print).
        start: start each session's worker; False: the caller drives its schedule step by step
            (`session.schedule.step()`: tests, benchmarks).
        clock: each session's schedule's clock (default time.perf_counter).
        carry: after a camera move, show the image of the view before carried to the new view
            until the new session's draft (`ViewportSession.carry`); False: nothing is shown
            before the draft (benchmarks compare the two).

    `log`: one dict per update (`kind`: first, objects, camera, settings, restyle or none;
    `objects`: names re-exported; `world`; `seconds`; `restyle_s` after a style change)."""

    def __init__(self, on_image: Callable[[], None] | None = None, draft: bool = True,
                 warn: Callable[[str], None] = print, start: bool = True,
                 clock: Callable[[], float] = time.perf_counter, carry: bool = True):
        self.sync = SceneSync(warn)
        self.on_image, self.draft, self.threaded, self.clock = on_image, draft, start, clock
        self.carry = carry
        self.values: dict | None = None
        self.view: tuple | None = None
        self.sensor: dict | None = None
        self.session: ViewportSession | None = None
        self.log: list[dict] = []
        self._rest: threading.Timer | None = None  # the restyle at rest of the last drag

    def update(self, depsgraph, settings) -> dict:
        """Sync a depsgraph's updates (view_update); restyle, or start new passes, as needed.

        Args:
            depsgraph: the evaluated depsgraph (its `updates` after the first call).
            settings: the scene's styletrace settings (`snapshot` reads them).

        Returns:
            This update's `log` entry.
        """
        start = time.perf_counter()
        first = self.values is None
        values = snapshot(settings)
        changes = None if first else changes_of(depsgraph.updates)
        synced = self.sync.sync(depsgraph, changes)
        entry = {"kind": "first" if first else "none", "objects": synced["objects"],
                 "world": synced["world"] and not first}
        old, self.values = self.values, values
        if first:
            pass
        elif synced["objects"] or entry["world"]:
            entry["kind"] = "objects"
        elif (any(old[k] != values[k] for k in PASS_KEYS + DENOISE_KEYS + SAMPLER_KEYS)
              or _rest(old) != _rest(values)):
            entry["kind"] = "settings"
        elif old["style"] != values["style"]:
            # a slider's new value at once, one point per pixel; the whole look at rest
            seconds = self.session.restyle(values["style"], quick=True) if self.session else None
            entry["kind"] = "restyle" if seconds is not None else "settings"
            entry["restyle_s"] = seconds
            if seconds is not None:
                self._rest_later(values["style"])
        elif changes.camera:  # the view through a moved camera reaches `set_view`
            entry["kind"] = "camera"
        if entry["kind"] in ("first", "objects", "settings"):
            self.restart()
        entry["seconds"] = time.perf_counter() - start
        self.log.append(entry)
        return entry

    def _rest_later(self, style: dict) -> None:
        """Restyle the whole buffer with `style` once no newer value came for REST_S seconds, in
        a timer's thread (the session's image then changes; Blender's poll redraws)."""
        if self._rest is not None:
            self._rest.cancel()
        session = self.session
        self._rest = threading.Timer(REST_S, self._at_rest, (session, style))
        self._rest.daemon = True
        self._rest.start()

    def _at_rest(self, session, style: dict) -> float | None:
        if session is not self.session or session is None or style != self.values["style"]:
            return None  # a newer session or value: its own rest restyle follows
        return session.restyle(style)

    def settle(self) -> float | None:
        """The restyle at rest now, without waiting for REST_S (tests, benchmarks).

        Returns:
            Its seconds, or None where no drag is pending.
        """
        timer, self._rest = self._rest, None
        if timer is None:
            return None
        timer.cancel()
        return self._at_rest(self.session, self.values["style"])

    def set_view(self, view_matrix, window_matrix, width: int, height: int) -> bool:
        """The region's camera (view_draw): a new view starts new passes without exporting.

        Args:
            view_matrix: the region's world -> view matrix (4 x 4, `region_data.view_matrix`).
            window_matrix: its projection (4 x 4, `region_data.window_matrix`).
            width, height: the region's size in pixels.

        Returns:
            Whether the view changed."""
        key = (tuple(map(tuple, view_matrix)), tuple(map(tuple, window_matrix)), width, height)
        if key == self.view:
            return False
        self.view = key
        return self.set_sensor(view_sensor(view_matrix, window_matrix, width, height, 1))

    def set_sensor(self, sensor: dict) -> bool:
        """Render through `sensor`: new passes once the settings are known (after `update`).

        Args:
            sensor: a sensor description with its `film` (e.g. `view_sensor`'s, `camera.sensor`'s);
                its sampler is replaced by one of the settings' samples.

        Returns:
            True.
        """
        self.sensor = sensor
        start = time.perf_counter()
        if self.values is not None:
            self.restart(moved=True)
            self.log.append({"kind": "camera", "objects": [], "world": False,
                             "seconds": time.perf_counter() - start})
        return True

    def restart(self, moved: bool = False) -> None:
        """Stop the running session and start one on the kept objects and the current view.

        Args:
            moved: the view moved (nothing else changed): the new session shows the old one's
                image carried to the new view until its draft (where `carry`).
        """
        old = self.session
        if old is not None:
            old.stop()
        if self.sensor is None or self.values is None:
            return
        film = self.sensor["film"]
        w, h = film["width"], film["height"]
        sensor = dict(self.sensor, sampler={"type": self.values.get("sampler", SAMPLER_DEFAULT),
                                            "sample_count": self.values["samples"]})
        # both films' dicts are made now, on the main thread: the sync changes after this call
        desc = {size: self.sync.scene_dict(dict(sensor, film=dict(film, width=size[0],
                                                                   height=size[1])))
                for size in ((w, h), draft_size(w, h))}
        sync = self.sync

        def scene_dict(width: int, height: int) -> dict:
            # called by the session under TURNS: no scene made from the kept meshes is traced
            # while the moved ones take their new vertices
            sync.place_moved()
            return desc[(width, height)]

        self.session = ViewportSession(
            scene_dict, (w, h), self.values, self.on_image,
            self.draft, self.clock, before=old if moved and self.carry else None,
        )
        if self.threaded:
            self.session.start()

    def close(self) -> None:
        if self._rest is not None:
            self._rest.cancel()
        if self.session is not None:
            self.session.stop()
            self.session = None


__all__ = ["Viewport", "ViewportSession", "snapshot", "load_view_scene", "restylable", "TURNS",
           "REST_S"]
