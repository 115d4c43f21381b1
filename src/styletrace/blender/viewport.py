"""Rendered shading in the 3D viewport: a progressive session per view, fed by `viewport_sync`.

    vp = Viewport()
    vp.update(depsgraph, settings)                     # view_update: sync what changed
    vp.set_view(view_matrix, window_matrix, w, h)      # view_draw: the region's camera
    image, label = vp.session.latest()                 # the newest image, drawn with `gpu`

A `ViewportSession` renders in a worker thread a draft (1 spp, at most `DRAFT_PIXELS` pixels),
then F12's passes and finisher, denoised where `denoise_now` says so. A style change restyles the
recorded buffer; any other change starts a new session on the kept Mitsuba objects. All Dr.Jit work
runs under the lock `JIT`. Blender's hooks: `view_update`, `view_draw`, `free`. Design:
docs/design/viewport.md.
"""
from __future__ import annotations

import gc
import threading
import time
import traceback
from types import SimpleNamespace
from typing import Any, Callable

import numpy as np

from styletrace.blender import f12
from styletrace.blender.properties import settings_integrator_values, style_values
from styletrace.blender.viewport_sync import SceneSync, changes_of, view_sensor
from styletrace.denoise.draft import available as denoise_available
from styletrace.denoise.finishers import Denoised, Expectation, plan_finisher
from styletrace.denoise.progressive import PREVIEW_K, PREVIEW_QUALITY, denoise_now
from styletrace.errors import StyletraceError
from styletrace.frontends import api
from styletrace.gate import dr, mi
from styletrace.lookdev.buffer import MAX_SAMPLES
from styletrace.lookdev.record import Recorded
from styletrace.lookdev.restyle import restyle as lookdev_restyle
from styletrace.lookdev.restyle import slots_for
from styletrace.lookdev.slider import quick_restyle
from styletrace.pipeline.resolve import resolve
from styletrace.pipeline.runner import Runner

#: the draft's largest film (pixels): a larger view is drafted at a reduced resolution
DRAFT_PIXELS = 160 * 120
DRAFT_QUALITY = "balanced"
#: seconds without a new style value after which a drag is at rest: the whole buffer is restyled
REST_S = 0.25
#: one Dr.Jit user at a time: sessions replaced by a newer one finish their pass under it
JIT = threading.Lock()
#: the render settings that are not the style's: a change starts new passes
PASS_KEYS = ("samples", "spp", "seed", "pass_spp")
DENOISE_KEYS = ("denoise", "denoise_quality", "denoise_footprint")


def snapshot(settings) -> dict:
    """The settings the viewport renders with, read on Blender's main thread.

    Args:
        settings: the scene's styletrace settings (a SceneSettings, `scene.styletrace`).

    Returns:
        `style` (the style slot's values, `style_values`), `integrator` (the `stylized`
        integrator's), `samples`, `spp` (0: auto), `seed`, `pass_spp` (ints), `denoise`,
        `denoise_quality`, `denoise_footprint` (strings).
    """
    return {"style": style_values(settings), "integrator": settings_integrator_values(settings),
            **{k: int(getattr(settings, k)) for k in PASS_KEYS},
            **{k: str(getattr(settings, k)) for k in DENOISE_KEYS}}


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


def draft_size(width: int, height: int, limit: int = DRAFT_PIXELS) -> tuple[int, int]:
    """The draft's film: the view's size scaled down (same aspect) to at most `limit` pixels.

    Args:
        width, height: the view's size in pixels.
        limit: the draft's most pixels (default `DRAFT_PIXELS`); a smaller view keeps its size.

    Returns:
        (width, height) of the draft, each at least 1.
    """
    scale = min(1.0, (limit / float(width * height)) ** 0.5)
    return max(1, round(width * scale)), max(1, round(height * scale))


class ViewportSession:
    """A view's progressive render in a worker thread. `latest()` is the newest image; `version`
    counts images.

    Args:
        scene_dict: a callable (width, height) -> the Mitsuba scene dict (`SceneSync.scene_dict`).
        width, height: the view's size in pixels.
        values: `snapshot` of the settings.
        on_image: called (in the worker) after each new image; None: nothing is called.
        draft: render the draft first.

    `stats`: `draft_s`, `last_pass_s` (seconds from the start), `denoise_s` (seconds per
    denoising); `passes_run` counts passes; `error`: a refusal's line (None without one)."""

    def __init__(self, scene_dict: Callable[[int, int], dict], width: int, height: int,
                 values: dict, on_image: Callable[[], None] | None = None, draft: bool = True):
        self.scene_dict, self.size, self.values = scene_dict, (width, height), values
        self.on_image = on_image or (lambda: None)
        self.image: np.ndarray | None = None
        self.label = ""
        self.version = 0
        self.passes_run = 0
        self.buffer = None
        self.recorded = False  # the passes record a buffer (restyles need no new pass)
        self.style: dict | None = None  # a restyled style: later passes are shown restyled
        self.error: str | None = None
        self.spp_done = 0
        self.stats: dict = {"started": time.perf_counter()}
        self._draft = draft
        #: the next denoised image is a preview: none at full size has been shown yet
        self._previewing = True
        self._lock = threading.Lock()
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, name="styletrace-viewport", daemon=True)

    def start(self) -> "ViewportSession":
        """Start the worker. Returns: this session."""
        self._thread.start()
        return self

    def stop(self, wait: float = 0.0) -> None:
        """Ask the worker to stop after its pass under way.

        Args:
            wait: seconds to wait at most for the worker to end; 0 returns at once.
        """
        self._stop.set()
        if wait and self._thread.is_alive():
            self._thread.join(wait)

    def join(self, timeout: float | None = None) -> None:
        """Wait for the worker to end.

        Args:
            timeout: seconds to wait at most; None waits until it ends.
        """
        self._thread.join(timeout)

    @property
    def done(self) -> bool:
        """Whether the worker has ended (or never started)."""
        return not self._thread.is_alive()

    def latest(self) -> tuple[np.ndarray | None, str]:
        """The newest image (H x W x 3 float32; None before the first) and its label."""
        with self._lock:
            return self.image, self.label

    def _show(self, image: np.ndarray, label: str) -> None:
        with self._lock:
            self.image, self.label = np.array(image, dtype=np.float32), label
            self.version += 1
        self.on_image()

    def _job(self, sc, spp: int, pass_spp: int, **override) -> Any:
        values = {**self.values["integrator"], "aovs": False, **override}
        integ = api.make_integrator_from(values)
        sampling = SimpleNamespace(samples=self.values["samples"], spp=spp,
                                   seed=self.values["seed"], pass_spp=pass_spp)
        return resolve(f12.job(sc, integ, sampling), scene=sc)

    def _run(self) -> None:
        try:
            if self._draft:
                self._run_draft()
            self._run_passes()
        except StyletraceError as exc:
            self.error = str(exc).strip().splitlines()[0]
        except Exception as exc:  # a bug or Mitsuba's refusal: one line, the finished image kept
            self.error = f"{type(exc).__name__}: {exc}".splitlines()[0]
        if not self._stop.is_set():
            # the garbage of this session and those before it (scenes, buffers, kernels' arrays)
            # collected now, while the view is idle, not in the next session's draft (cel on the
            # interior at 512 x 512, sessions in a row: drafts 0.54, 0.78, 0.90 s after an edit
            # without; 0.22 to 0.35 s in 11 of 12 with)
            gc.collect()

    def _run_draft(self) -> None:
        """The draft: one camera sample of the passes' children (at most `budget.CHILDREN`) at
        the draft's size, denoised at every Denoise setting as auto denoises: the expectation,
        previewed, for a style of several children (its bands, not a style of single paths
        blurred), else OIDN's image denoiser."""
        w, h = draft_size(*self.size)
        with JIT:
            if self._stop.is_set():
                return
            sc = load_view_scene(self.scene_dict(w, h))
            children = self.values["style"].get("inner_samples") or str(draft_children(
                self.values["style"]["style"]))
            resolved = self._job(sc, 1, 1, inner_samples=children)
            # whatever Denoise says: the draft is a glimpse, not F12's image
            runner = plan_finisher(resolved, method="auto", label="<draft>")[0]
            prog = next(iter(runner.passes()))
            image, label = prog.image, "draft"
            if isinstance(runner.finisher, Expectation):
                image = runner.finisher.job.preview(PREVIEW_K, PREVIEW_QUALITY)[0]
                label = "draft, denoised"
            elif denoise_available():
                from styletrace.denoise.image import finish_denoised_image
                image = finish_denoised_image(sc, prog, self.values["seed"], DRAFT_QUALITY)[0]
                label = "draft, denoised"
            self.passes_run += 1
        self.stats["draft_s"] = time.perf_counter() - self.stats["started"]
        self._show(image[..., :3], f"{label} ({w}x{h}, 1 spp)")

    def _runner(self, resolved) -> Runner:
        """F12's runner of `resolved` (`f12.run_f12`'s finisher plan), recording the buffer to
        restyle where it can: the passes' (Denoise off) or the denoised one (expectation)."""
        v = self.values
        plan = dict(method=v["denoise"], quality=v["denoise_quality"], label="<viewport>",
                    footprint=v["denoise_footprint"])
        if self.size[0] * self.size[1] * resolved.spp <= MAX_SAMPLES:
            try:
                return plan_finisher(resolved, keep=self._keep, **plan)[0]
            except StyletraceError:  # not recordable (e.g. its estimator): refused again below
                pass
        # unrecorded (over the buffer's cap, or not recordable): a style change retraces
        return plan_finisher(resolved, **plan)[0]

    def _keep(self, buf) -> None:
        self.buffer = buf

    def _run_passes(self) -> None:
        v = self.values
        with JIT:
            if self._stop.is_set():
                return
            sc = load_view_scene(self.scene_dict(*self.size))
            runner = self._runner(self._job(sc, v["spp"], v["pass_spp"]))
            finisher = runner.finisher
            denoised = isinstance(finisher, Denoised)
            # Denoise image keeps no buffer: its restyle would not be the denoised image
            self.recorded = isinstance(finisher, Recorded) or (
                isinstance(finisher, Expectation) and finisher.keep is not None)
            passes = runner.passes()
        total = -(-runner.resolved.spp // v["pass_spp"])  # spp 0: the split of samples
        self.stats["denoise_s"] = []
        since = 0.0  # seconds of passes since the last denoised image
        for k in range(1, total + 1):
            if self._stop.is_set():
                return
            with JIT:
                start = time.perf_counter()
                prog = next(passes, None)
                if prog is None:
                    return
                self.passes_run += 1
                self.spp_done = prog.spp_done
                since += time.perf_counter() - start
                label = f"pass {k}/{total}, {prog.spp_done} spp"
                if not denoised:
                    self.buffer = getattr(finisher, "recorded", None)
                    self._show(self._styled(prog.image), label)
                elif finisher.ready(prog):
                    if k < total and not denoise_now(k, total, since, self.stats["denoise_s"]):
                        continue  # the last denoised image stays
                    self._denoised(runner, prog, label, k == total)
                    since = 0.0
                else:
                    self._show(self._styled(prog.image), label)
            self.stats["last_pass_s"] = time.perf_counter() - self.stats["started"]
        self._warm_quick_restyle()

    def _denoised(self, runner, prog, label: str, last: bool) -> None:
        """Show the denoised images of a pass, under `JIT`: a preview (`ExpectationJob.preview`)
        unless this is the last pass and a full-size denoised image is on screen already; after
        the last pass, F12's finisher. Each is restyled with a style changed meanwhile."""
        finisher = runner.finisher
        if isinstance(finisher, Expectation) and (not last or self._previewing):
            start = time.perf_counter()
            image, buf = finisher.job.preview(PREVIEW_K, PREVIEW_QUALITY)
            self.stats["denoise_s"].append(time.perf_counter() - start)
            if self.recorded:  # the preview's buffer restyles until the finisher's replaces it
                self.buffer = buf
            self._previewing = False
            self._show(self._styled(image), label + ", denoised (preview)")
        if last or not isinstance(finisher, Expectation):
            start = time.perf_counter()
            # Expectation: `_keep` gets the denoised buffer (coverage points: its own object,
            # which later passes leave as it is)
            image = runner.finish(prog)
            self.stats["denoise_s"].append(time.perf_counter() - start)
            self._show(self._styled(image), label + ", denoised")

    def _styled(self, image: np.ndarray) -> np.ndarray:
        """`image`, or the buffer restyled where the style changed since the passes started."""
        if self.style is not None and self.buffer is not None:
            return _restyled(self.buffer, self.style)
        return image[..., :3]

    def _warm_quick_restyle(self) -> None:
        """Trace and compile the restyles of the final buffer before the first drag needs them:
        the quick one's one-point-per-pixel view and kernel (`lookdev.slider`), and the whole
        buffer's kernel, for the current style (θ is a kernel input: later values reuse them)."""
        if not self.recorded or self.buffer is None or self._stop.is_set():
            return
        with JIT:
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
            The seconds taken; 0.0 where a pass or a denoising holds Dr.Jit (`JIT`): the style is
            then kept and the worker shows its next image with it, without waiting here; None
            where there is no buffer to restyle yet or it cannot take the style (then the caller
            starts new passes)."""
        buf = self.buffer
        if buf is None or not restylable(buf, style):
            return None
        if not JIT.acquire(blocking=not quick):
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
            JIT.release()
        how = "restyled at one point per pixel" if quick else "restyled"
        self._show(image, f"{how}, {self.spp_done} spp")
        return seconds


def draft_children(style: str) -> int:
    """Children per camera sample of the draft: the budget's auto count for `style`
    (`pipeline.budget.CHILDREN` at most; 1 for a style without children).

    Args:
        style: the style's registry name.

    Returns:
        n >= 1.
    """
    from styletrace.pipeline.budget import CHILDREN
    from styletrace.styles import style_class
    return max(1, min(style_class(style).default_inner, CHILDREN))


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
    Dr.Jit, so it needs no `JIT`).

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

    `log`: one dict per update (`kind`: first, objects, camera, settings, restyle or none;
    `objects`: names re-exported; `world`; `seconds`; `restyle_s` after a style change)."""

    def __init__(self, on_image: Callable[[], None] | None = None, draft: bool = True,
                 warn: Callable[[str], None] = print):
        self.sync = SceneSync(warn)
        self.on_image, self.draft = on_image, draft
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
        elif (any(old[k] != values[k] for k in PASS_KEYS + DENOISE_KEYS)
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
            self.restart()
            self.log.append({"kind": "camera", "objects": [], "world": False,
                             "seconds": time.perf_counter() - start})
        return True

    def restart(self) -> None:
        """Stop the running session and start one on the kept objects and the current view."""
        if self.session is not None:
            self.session.stop()
        if self.sensor is None or self.values is None:
            return
        film = self.sensor["film"]
        w, h = film["width"], film["height"]
        sensor = dict(self.sensor, sampler={"type": "independent",
                                            "sample_count": self.values["samples"]})
        # both films' dicts are made now, on the main thread: the sync changes after this call
        desc = {size: self.sync.scene_dict(dict(sensor, film=dict(film, width=size[0],
                                                                   height=size[1])))
                for size in ((w, h), draft_size(w, h))}
        self.session = ViewportSession(
            lambda width, height: desc[(width, height)], w, h, self.values, self.on_image,
            self.draft,
        ).start()

    def close(self) -> None:
        if self._rest is not None:
            self._rest.cancel()
        if self.session is not None:
            self.session.stop()
            self.session = None


__all__ = [
    "Viewport", "ViewportSession", "snapshot", "draft_size", "denoise_now", "JIT", "DRAFT_PIXELS",
]


# ---- Blender's side: the engine's view_update and view_draw --------------------------------------

#: the viewports of the live engines, by `RenderEngine.as_pointer()`
VIEWS: dict[int, Viewport] = {}
#: seconds between the main thread's checks for a new image (Blender's UI is not touched from the
#: worker: a timer asks for the redraw)
REDRAW_S = 0.05


def view_update(engine, context, depsgraph) -> None:
    """`RenderEngine.view_update`: sync the depsgraph's updates into this engine's viewport.

    Args:
        engine: the `RenderEngine`; its pointer keys `VIEWS`, its status line shows a refusal.
        context: Blender's context (unused).
        depsgraph: the evaluated depsgraph; its scene's styletrace settings are read.

    A refusal or a bug closes the viewport and shows one line in the status (not raised).
    """
    key = engine.as_pointer()
    vp = VIEWS.get(key)
    if vp is None:
        vp = VIEWS[key] = Viewport(warn=lambda m: print(m))
        vp.engine, vp.drawn = engine, -1
        import bpy
        bpy.app.timers.register(lambda: _poll(key), first_interval=REDRAW_S)
    try:
        vp.update(depsgraph, depsgraph.scene.styletrace)
    except StyletraceError as exc:
        vp.close()
        engine.update_stats("", f"styletrace: {str(exc).strip().splitlines()[0]}")
    # Mitsuba's refusal of the exported scene, or a bug: one line, the trace on stderr
    except Exception as exc:
        traceback.print_exc()
        vp.close()
        engine.update_stats("", f"styletrace: {type(exc).__name__}: {exc}".splitlines()[0])


def _poll(key: int) -> float | None:
    """Ask for a redraw where the session has a newer image; None ends the timer."""
    vp = VIEWS.get(key)
    if vp is None:
        return None
    s = vp.session
    if s is not None and (s.version != vp.drawn or s.error):
        try:
            vp.engine.tag_redraw()
        except ReferenceError:  # the engine was freed (the view left Rendered mode)
            free_key(key)
            return None
    return REDRAW_S


def view_draw(engine, context, depsgraph) -> None:
    """`RenderEngine.view_draw`: follow the region's camera; draw the newest image.

    Args:
        engine: the `RenderEngine` (its viewport in `VIEWS`; none: nothing is drawn).
        context: Blender's context: its `region` and `region_data` give the view and size.
        depsgraph: the evaluated depsgraph; its scene's colour management applies.
    """
    vp = VIEWS.get(engine.as_pointer())
    if vp is None:
        return
    region, rv3d = context.region, context.region_data
    vp.set_view(rv3d.view_matrix, rv3d.window_matrix, region.width, region.height)
    s = vp.session
    if s is None:
        return
    image, label = s.latest()
    engine.update_stats("", f"styletrace: {s.error or label or 'starting'}")
    if image is None:
        return
    vp.drawn = s.version
    draw_view_image(engine, depsgraph.scene, image, region.width, region.height)


#: Blender shifts a region's pixel space by 0.01 px (GLA_PIXEL_OFS); a texture drawn at
#: (-PIXEL_OFFSET, -PIXEL_OFFSET) lands on the pixel centres, unblurred
#: (tests/blender/test_viewport_draw.py)
PIXEL_OFFSET = 0.01


def draw_view_image(engine, scene, image: np.ndarray, width: int, height: int) -> None:
    """Draw `image` over the region, through the view's colour management
    (`bind_display_space_shader`).

    Args:
        engine: the `RenderEngine` whose display-space shader is bound.
        scene: the Blender scene whose view transform, look and exposure apply.
        image: H x W x 3 floats, linear, top row first; stretched to the region.
        width, height: the region's size in pixels.
    """
    import gpu
    from gpu_extras.presets import draw_texture_2d
    h, w = image.shape[:2]
    px = np.ones((h, w, 4), np.float32)
    px[..., :3] = image[::-1]
    data = gpu.types.Buffer("FLOAT", w * h * 4, px.reshape(-1))
    texture = gpu.types.GPUTexture((w, h), format="RGBA16F", data=data)
    gpu.state.blend_set("ALPHA_PREMULT")
    engine.bind_display_space_shader(scene)
    draw_texture_2d(texture, (-PIXEL_OFFSET, -PIXEL_OFFSET), width, height)
    engine.unbind_display_space_shader()
    gpu.state.blend_set("NONE")


def free_key(key: int) -> None:
    """Forget the viewport of an engine and stop its session.

    Args:
        key: the engine's `as_pointer()`; a key with no viewport is ignored.
    """
    vp = VIEWS.pop(key, None)
    if vp is not None:
        vp.close()


def free_all(*_args) -> None:
    """Stop and forget every viewport: a `load_pre` handler, since Blender drops the engines of
    the old file without their `__del__` reaching `free`.

    Args:
        _args: what Blender passes a handler (the file path, ...), unused.
    """
    for key in list(VIEWS):
        free_key(key)


def register_viewport() -> None:
    """Free the viewports whenever Blender loads a file (`free_all`)."""
    import bpy
    # persistent: Blender keeps the handler across the loads it is there for
    bpy.app.handlers.persistent(free_all)
    if free_all not in bpy.app.handlers.load_pre:
        bpy.app.handlers.load_pre.append(free_all)


def unregister_viewport() -> None:
    """Remove the load handler and free every viewport."""
    import bpy
    if free_all in bpy.app.handlers.load_pre:
        bpy.app.handlers.load_pre.remove(free_all)
    free_all()


def free(engine) -> None:
    """The engine is going away (`RenderEngine.__del__`): stop its session.

    Args:
        engine: the `RenderEngine`; one already freed by Blender (ReferenceError) is ignored.
    """
    try:
        free_key(engine.as_pointer())
    except ReferenceError:
        pass
