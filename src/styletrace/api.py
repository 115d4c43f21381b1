"""The Python API: load a scene, build the `stylized` integrator, render in passes.

    import styletrace
    img = styletrace.render("cornell-box", style="cel", spp=16, inner=8)   # H x W x 3 float32, linear

Large renders run as several passes of at most `LANES_PER_PASS` camera samples, so memory stays
bounded whatever spp and inner sample counts are; each pass has its own seed derived from `seed`,
so the same seed reproduces the same image exactly.
"""
from __future__ import annotations

import math
import os
from dataclasses import dataclass
from typing import Any, Callable, Iterator

from .jit import backend
from .runtime import init

backend()  # Dr.Jit picks its libLLVM when first imported: choose it (and the variant) before that

import mitsuba as mi  # noqa: E402
import numpy as np  # noqa: E402

from .arguments import check_passes_args, check_render_args, check_scene, scene_problem  # noqa: E402
from .errors import SceneError  # noqa: E402
from .images import save_safely, write_image  # noqa: E402
from .plugins.integrator import StylizedIntegrator  # noqa: E402
from .plugins.scene_defaults import resolve as resolve_defaults  # noqa: E402
from .plugins.scenes import BUILTIN, DEFAULT  # noqa: E402

#: Camera samples per pass: bounds the memory of the megakernel's state (~ a few hundred bytes each).
LANES_PER_PASS = 1 << 20


def first_line(exc: BaseException) -> str:
    text = str(exc).strip()
    lines = [ln.strip() for ln in text.splitlines() if ln.strip()]
    # Mitsuba prefixes the real cause with context lines; the last line is the most specific.
    return lines[-1] if lines else type(exc).__name__


def _size(width, height, keys=("width", "height")) -> dict[str, int]:
    """The given image size as keyword arguments, leaving out what was not given."""
    return {k: v for k, v in zip(keys, (width, height)) if v}


def scene_dict(name: str, width: int | None = None, height: int | None = None) -> dict[str, Any]:
    if name not in BUILTIN:
        raise SceneError(f"unknown built-in scene '{name}': available are {', '.join(sorted(BUILTIN))}")
    return BUILTIN[name](**_size(width, height))


def load_scene(scene: Any = None, width: int | None = None, height: int | None = None) -> mi.Scene:
    """A built-in name, a Mitsuba XML path, a scene dict or an mi.Scene -> mi.Scene."""
    init()
    if scene is None:
        scene = DEFAULT
    if isinstance(scene, mi.Scene):
        check_scene(scene, "the mi.Scene")
        if width or height:
            size = scene.sensors()[0].film().size()
            if (width and width != size[0]) or (height and height != size[1]):
                raise SceneError("width/height cannot change an already loaded mi.Scene; pass a dict or file")
        return scene
    if isinstance(scene, dict):
        if width or height:
            raise SceneError("width/height apply to built-in scenes and XML files; set the film size in the dict")
        try:
            loaded = mi.load_dict(scene)
        except Exception as exc:  # Mitsuba raises RuntimeError with several context lines
            raise SceneError(f"cannot load scene dict: {first_line(exc)}") from None
        problem = scene_problem(loaded, "the scene dict")
        if problem is not None:
            del loaded  # see arguments.scene_problem: a refused scene must not outlive this call
            raise SceneError(problem)
        return loaded
    if not isinstance(scene, (str, os.PathLike)):
        raise SceneError(f"bad scene {scene!r}: expected a built-in name ({', '.join(sorted(BUILTIN))}), an XML "
                         f"path, a scene dict or an mi.Scene")
    name = os.fspath(scene)
    if name in BUILTIN:
        try:
            return mi.load_dict(scene_dict(name, width, height))
        except Exception as exc:
            raise SceneError(f"cannot load built-in scene '{name}': {first_line(exc)}") from None
    if not name.lower().endswith(".xml") and not os.path.exists(name):
        raise SceneError(f"unknown scene '{name}': expected a built-in scene ({', '.join(sorted(BUILTIN))}) "
                         f"or a Mitsuba XML file")
    if not os.path.isfile(name):
        raise SceneError(f"scene file '{name}' does not exist")
    try:
        loaded = mi.load_file(name, **_size(width, height, ("resx", "resy")))
    except Exception as exc:
        raise SceneError(f"cannot load scene file '{name}': {first_line(exc)}") from None
    problem = scene_problem(loaded, f"scene file '{name}'")
    if problem is not None:
        del loaded  # see arguments.scene_problem: a refused scene must not outlive this call
        raise SceneError(problem)
    if width or height:
        size = loaded.sensors()[0].film().size()
        if (width and width != size[0]) or (height and height != size[1]):
            raise SceneError(f"scene file '{name}' fixes its film size {size[0]}x{size[1]}; to resize it, "
                             f"write the film's width/height as $resx/$resy in the XML")
    return loaded


def make_integrator(style: str | None = None, inner: Any = None, estimator: str | None = None,
                    **params: Any) -> StylizedIntegrator:
    """A `stylized` integrator. Integrator properties (stylize, stylize_depth, max_depth, rr_depth) and the
    style's parameters go in **params under their names; what is not given takes the default of
    `plugins.settings` (`inner`: the style's own count, or one per level: (8, 4))."""
    given = {"style": style, "inner_samples": inner, "estimator": estimator, **params}
    return make_integrator_from({k: v for k, v in given.items() if v is not None})


def make_integrator_from(values: dict[str, Any]) -> StylizedIntegrator:
    """A `stylized` integrator from its property values (style, style parameters, inner_samples, ...)."""
    init()
    return StylizedIntegrator.from_values(values)


def pass_seed(seed: int, index: int) -> int:
    """Seed of pass `index`: distinct passes and distinct user seeds get unrelated sample streams."""
    return (seed * 0x9E3779B1 + index * 0x85EBCA6B + 0x27D4EB2F) & 0xFFFFFFFF


@dataclass
class Progress:
    spp_done: int
    spp_total: int
    image: np.ndarray  # the average of all passes so far


def passes(scene: mi.Scene, integrator: mi.Integrator, spp: int, seed: int = 0,
           lanes_per_pass: int = LANES_PER_PASS) -> Iterator[Progress]:
    """Render `spp` samples per pixel in passes; yield the running average after each pass."""
    check_passes_args(scene, integrator, spp, seed)
    integrator = resolve_defaults(scene, integrator)[0]  # scene-relative 'auto' style values (scene_defaults)
    size = scene.sensors()[0].film().crop_size()
    pixels = int(size[0]) * int(size[1])
    per_pass = max(1, min(spp, lanes_per_pass // max(pixels, 1)))
    total = None
    done = 0
    index = 0
    while done < spp:
        n = min(per_pass, spp - done)
        img = mi.render(scene, integrator=integrator, spp=n, seed=pass_seed(seed, index))
        arr = np.array(img, dtype=np.float64)[..., :3]
        total = arr * n if total is None else total + arr * n
        done += n
        index += 1
        yield Progress(done, spp, (total / done).astype(np.float32))


def pass_count(scene: mi.Scene, spp: int, lanes_per_pass: int = LANES_PER_PASS) -> int:
    size = scene.sensors()[0].film().crop_size()
    per_pass = max(1, min(spp, lanes_per_pass // max(int(size[0]) * int(size[1]), 1)))
    return math.ceil(spp / per_pass)


def render(scene: Any = None, style: str | None = None, spp: int = 16, inner: Any = None,
           estimator: str | None = None, seed: int = 0, width: int | None = None, height: int | None = None,
           integrator: mi.Integrator | None = None, callback: Callable[[Progress], None] | None = None,
           **params: Any) -> np.ndarray:
    """Render with a style; returns float32 H x W x 3 linear radiance.

    `scene`: built-in name ('cornell-box', 'dragon', 'furnace'), XML path, scene dict or mi.Scene.
    Integrator keywords (stylize, stylize_depth, max_depth, rr_depth) and the style's parameters go
    in **params; what is not given takes the integrator's defaults (`plugins.settings`: identity, direct,
    the style's inner count). Pass `integrator=` to use a prebuilt one (then style and params are ignored).
    """
    check_render_args(spp, seed, integrator)
    sc = load_scene(scene, width, height)
    if integrator is None:
        integrator = make_integrator(style=style, inner=inner, estimator=estimator, **params)
    image = None
    for prog in passes(sc, integrator, spp, seed):
        image = prog.image
        if callback is not None:
            callback(prog)
    return image


__all__ = ["render", "load_scene", "make_integrator", "make_integrator_from", "passes", "resolve_defaults", "pass_count", "SceneError",
           "Progress", "StylizedIntegrator", "write_image", "save_safely"]
