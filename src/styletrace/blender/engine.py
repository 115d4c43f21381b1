"""The `styletrace` render engine: F12, Render Animation, material previews and the viewport.

F12 is one pipeline run (`f12.run_f12`): progress after each pass (`update_progress`), the image so
far shown, `test_break` asked between passes (a cancel keeps the finished passes). Render passes:
the error AOVs (`aovs`), a line mask with lines, a Noisy pass where Denoise is on (then no error
passes), and the data passes (Depth, Normal, Vector, Position, UV, Mist, the indices,
Denoising Albedo, Emission, Cryptomatte object and material, their manifests in the result's
metadata) where the view layer asks for them (Cycles' switches; `f12.switches`,
docs/passes.md). "Record buffer" keeps the look-development buffer for restyles (`restyle`).
Each render uses its frame's seed; a cancel during Render Animation ends it (`animation`).
Previews render Blender's preview scene at their own budget (`preview`); Rendered shading is
`viewport`'s. Errors the user can cause are one-line Blender error reports. Docs: docs/blender.md.
"""
from __future__ import annotations

import time
import traceback

import bpy
import numpy as np

from styletrace.blender import animation, f12, motion, preview, restyle, viewport_hooks
from styletrace.denoise.finishers import Denoised
from styletrace.errors import StyletraceError
from styletrace.kernel.data_passes import MANIFEST

COMBINED = "Combined"
#: what the last render did: camera samples per pixel finished and asked for, whether it was
#: cancelled, seconds
LAST: dict = {}
#: the same for the last material preview
PREVIEW: dict = {}


def _rows(image: np.ndarray, channels: int) -> np.ndarray:
    """H x W x C (top row first) -> Blender's pixel rows (bottom row first), `channels` wide; RGB
    gets an alpha of 1."""
    h, w = image.shape[:2]
    img = image.reshape(h, w, -1)[::-1]
    if channels == 4 and img.shape[-1] < 4:
        out = np.ones((h, w, 4), np.float32)
        out[..., :3] = img[..., :3]
        return out.reshape(-1, 4)
    return np.ascontiguousarray(img[..., :channels], dtype=np.float32).reshape(-1, channels)


def _put(render_pass, image: np.ndarray, channels: int) -> None:
    """Write an image into a render pass (`_rows`' layout). foreach_set takes the buffer at once:
    assigning `rect` walks it value by value (about 10 ms a pass at 128 x 128, on every progress
    update)."""
    render_pass.rect.foreach_set(_rows(image, channels).ravel())


def _message(exc: BaseException) -> str:
    text = str(exc).strip().splitlines()
    return text[-1] if text else type(exc).__name__


class StyletraceEngine(bpy.types.RenderEngine):
    bl_idname = "STYLETRACE"
    bl_label = "styletrace"
    bl_use_preview = True
    bl_use_postprocess = True

    def __del__(self):
        viewport_hooks.free(self)

    def view_update(self, context, depsgraph):
        """Rendered shading: sync the edits (`viewport_hooks.view_update`)."""
        viewport_hooks.view_update(self, context, depsgraph)

    def view_draw(self, context, depsgraph):
        """Rendered shading: draw the newest progressive image (`viewport_hooks.view_draw`)."""
        viewport_hooks.view_draw(self, context, depsgraph)

    def stop_requested(self) -> bool:
        """Esc was pressed (Blender's `test_break`); a method of our own, so that a test can
        press it."""
        return self.test_break()

    def progress(self, fraction: float, status: str) -> None:
        """Blender's progress bar and status line; a method of our own, so that a test can read them
        (Blender's own `update_progress` cannot be replaced on a registered engine).

        Args:
            fraction: the progress, in [0, 1]. status: the status line's text.
        """
        self.update_progress(fraction)
        self.update_stats("", status)

    def update_render_passes(self, scene=None, renderlayer=None):
        st = scene.styletrace
        self.register_pass(scene, renderlayer, COMBINED, 4, "RGBA", "COLOR")
        if f12.error_passes(st):
            for name, channels, ids in f12.AOV_PASSES.values():
                self.register_pass(
                    scene, renderlayer, name, channels, ids, "COLOR" if channels == 3 else "VALUE"
                )
        if st.denoise != "off":
            self.register_pass(scene, renderlayer, f12.NOISY, 3, "RGB", "COLOR")
        if st.lines:
            self.register_pass(scene, renderlayer, f12.LINE_MASK, 1, "X", "VALUE")
        for key in f12.data_passes_of(renderlayer):
            for name, channels, ids, kind in f12.render_passes(key):
                self.register_pass(scene, renderlayer, name, channels, ids, kind)

    def render(self, depsgraph):
        try:
            self._render(depsgraph)
        except StyletraceError as exc:
            self._report({"ERROR"}, _message(exc))
        # Mitsuba's refusals of the exported scene, or a bug: one line, the trace on stderr
        except Exception as exc:
            traceback.print_exc()
            self._report({"ERROR"}, f"styletrace: {type(exc).__name__}: {_message(exc)}")

    def _report(self, kinds: set, message: str) -> None:
        """Blender's `report`; a material preview's go to `preview.report` instead."""
        (preview.report if self.is_preview else self.report)(kinds, message)

    def _settings(self, depsgraph):
        """The settings this render uses: a preview's budget (`preview.settings`), else the
        scene's with the seed of the frame (`animation.at_frame`)."""
        st = depsgraph.scene.styletrace
        if self.is_preview:
            return preview.settings(st)
        return animation.at_frame(st, depsgraph.scene.frame_current)

    def _render(self, depsgraph):
        st = self._settings(depsgraph)
        self.update_stats("", "styletrace: exporting the scene")
        data = () if self.is_preview else f12.data_passes_of(depsgraph.view_layer)
        # Render Animation's frames accumulate, carried along the motion (docs/temporal.md); F12
        # alone does not
        reuse = self.is_animation and not self.is_preview and bool(st.temporal_reuse)
        # each shape's object, for its motion (the view layer's Vector, or the history's)
        placements = {} if reuse or "vector" in data else None
        desc = f12.description(depsgraph, st, warn=lambda m: self._report({"WARNING"}, m),
                               placements=placements)
        sc = f12.load(desc)
        moves = (motion.frames_around(self, depsgraph, sc, placements)
                 if placements is not None else None)
        history = animation.HISTORY if reuse else None
        size = sc.sensors()[0].film().crop_size()
        w, h = int(size[0]), int(size[1])
        aovs = f12.error_passes(st)
        if not self.is_preview:  # a preview keeps the user's recorded buffer
            restyle.forget()
        runner = f12.run_f12(sc, st, aovs, restyle.keep if st.record_buffer else None, history)
        if runner.resolved.note:
            self._report({"WARNING"}, f"styletrace: {runner.resolved.note}")
        denoised = isinstance(runner.finisher, Denoised)
        if aovs:
            for name, channels, ids in f12.AOV_PASSES.values():
                self.add_pass(name, channels, ids)
        if denoised:
            self.add_pass(f12.NOISY, 3, "RGB")
        if st.lines:
            self.add_pass(f12.LINE_MASK, 1, "X")
        for key in data:
            for name, channels, ids, _ in f12.render_passes(key):
                self.add_pass(name, channels, ids)
        start = time.perf_counter()
        source = runner.passes()
        prog = None
        spp = runner.resolved.spp  # Camera samples, or the split of Samples (`f12.sampling`)
        total = runner.resolved.launches
        for k, prog in enumerate(source, start=1):
            self.progress(
                prog.spp_done / prog.spp_total,
                f"styletrace: pass {k}/{total}, {prog.spp_done}/"
                f"{prog.spp_total} spp, {time.perf_counter() - start:.1f} s",
            )
            self._show(prog.image, w, h)
            if self.stop_requested():
                break
        done = dict(spp_done=prog.spp_done if prog else 0, spp_total=spp,
                    cancelled=self.stop_requested(), seconds=time.perf_counter() - start)
        (PREVIEW if self.is_preview else LAST).update(done)
        # ends Render Animation after this frame (Blender sets its break flag on an error report)
        if self.is_animation and done["cancelled"]:
            self._report({"ERROR"}, animation.stop_message(
                depsgraph.scene.frame_current, done["spp_done"], spp))
        if prog is None:
            return
        # the data passes after the render's passes (a cancelled render traces none), before the
        # finish, which blends with the history they carry (a render not denoised has none)
        reuse = reuse and denoised
        extra = {}  # Blender's pass name: (H x W (x C) values, channels)
        # the history's passes and the view layer's, each once
        traced = tuple(dict.fromkeys(animation.REUSE_PASSES + data)) if reuse else data
        frame_passes = f12.data_passes(runner, traced, moves,
                                       f12.mist_of(depsgraph.scene))
        if reuse:
            scene = depsgraph.scene
            animation.frame_history(st, frame_passes, scene.frame_current == scene.frame_start)
        for key in data:
            for name, values, channels in f12.pass_values(key, frame_passes[key]):
                extra[name] = (values, channels)
        # the Cryptomatte manifests, where the compositor's Cryptomatte node finds them
        stamps = f12.stamp_fields(depsgraph.view_layer.name,
                                  frame_passes.get(MANIFEST, {}))
        if st.lines and not self.stop_requested():
            mask = f12.line_mask(sc, st, self.stop_requested)
            if mask is not None:
                extra[f12.LINE_MASK] = (mask, 1)
        image, noisy = None, (prog.image if denoised else None)
        # (cancelled before every tile had a pass: noisy)
        if noisy is not None and runner.finisher.ready(prog):
            self.progress(prog.spp_done / prog.spp_total, "styletrace: denoising")
            image = runner.finish(prog)
            LAST["seconds"] = time.perf_counter() - start
        self._write(prog, aovs, extra, w, h, image, noisy, stamps)

    def _show(self, image, w, h):
        result = self.begin_result(0, 0, w, h)
        _put(result.layers[0].passes[COMBINED], image, 4)
        self.update_result(result)
        self.end_result(result)

    def _write(self, prog, aovs, extra, w, h, image=None, noisy=None, stamps=None):
        """The render result: Combined (the image, else the passes' average), Noisy, the error
        AOVs, `extra`'s passes ({Blender's pass name: (values, channels)}: the line mask, the
        data passes), and `stamps` ({field: value}) in its metadata.
        Takes more than 7 parameters: each is one part of the result, gathered apart by
        `_render`."""
        if stamps:  # into the whole render's result (a begun one's metadata is not kept)
            final = self.get_result()
            for field, value in stamps.items():
                final.stamp_data_add_field(field, value)
        result = self.begin_result(0, 0, w, h)
        layer = result.layers[0]
        _put(layer.passes[COMBINED], prog.image if image is None else image, 4)
        if noisy is not None:
            _put(layer.passes[f12.NOISY], noisy, 3)
        if aovs:
            for key, (name, channels, _) in f12.AOV_PASSES.items():
                _put(layer.passes[name], np.nan_to_num(prog.aovs[key]), channels)
        for name, (value, channels) in extra.items():
            _put(layer.passes[name], value, channels)
        self.end_result(result)


#: Cycles' panels that also apply to styletrace (resolution, output, colour management, ...)
def _compatible_panels():
    skip = {"VIEWLAYER_PT_filter", "VIEWLAYER_PT_layer_passes"}
    for name in dir(bpy.types):
        panel = getattr(bpy.types, name)
        engines = getattr(panel, "COMPAT_ENGINES", None)
        if engines is not None and "BLENDER_RENDER" in engines and name not in skip:
            yield panel


def register_engine():
    bpy.utils.register_class(StyletraceEngine)
    for panel in _compatible_panels():
        panel.COMPAT_ENGINES.add(StyletraceEngine.bl_idname)


def unregister_engine():
    for panel in _compatible_panels():
        panel.COMPAT_ENGINES.discard(StyletraceEngine.bl_idname)
    bpy.utils.unregister_class(StyletraceEngine)
