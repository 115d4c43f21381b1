"""Loading a scene: a built-in name, a Mitsuba XML file (with defines and a new film size), a dict
or an mi.Scene.

    scene = load_scene("scene.xml", width=64, height=48, defines={"depth": "3"})

Every loaded scene gets canonical vertex normals (`normals`), so the same seed gives the same image
in every process; a refused scene raises `SceneError` with one line and does not outlive the call
(docs/design/refused_scenes.md).
"""
from __future__ import annotations

import os
import re
import warnings
from typing import Any

from styletrace.config.choices import SAMPLERS
from styletrace.errors import SceneError
from styletrace.gate import mi
from styletrace.images import PIXEL_FORMATS
from styletrace.normals import canonical_normals as _canonical
from styletrace.scene import xml_file as scene_file
from styletrace.scene.arguments import check_scene, scene_problem
from styletrace.scene.builtin import BUILTIN, DEFAULT
from styletrace.scene.plugins import init


def first_line(exc: BaseException) -> str:
    """The one line of an exception's message worth showing.

    Args:
        exc: the exception (Mitsuba's carry context lines before the cause).

    Returns:
        The message's last non-empty line, stripped; the exception's type name if it has none.
    """
    text = str(exc).strip()
    lines = [ln.strip() for ln in text.splitlines() if ln.strip()]
    # Mitsuba prefixes the real cause with context lines; the last line is the most specific.
    return lines[-1] if lines else type(exc).__name__


def _size(width, height, keys=("width", "height")) -> dict[str, int]:
    """The given image size as keyword arguments, leaving out what was not given."""
    return {k: v for k, v in zip(keys, (width, height)) if v}


def scene_dict(name: str, width: int | None = None, height: int | None = None,
               sampler: str | None = None) -> dict[str, Any]:
    """The dict of a built-in scene.

    Args:
        name: a key of `builtin.BUILTIN`.
        width, height: the film's size in pixels; None (or 0) keeps the scene's default.
        sampler: one of `config.choices.SAMPLERS`; None: the scene's own (`owen_sobol`).

    Returns:
        The Mitsuba scene dict.

    Raises:
        SceneError: an unknown name or sampler.
    """
    if name not in BUILTIN:
        raise SceneError(f"unknown built-in scene '{name}': available are "
                         f"{', '.join(sorted(BUILTIN))}")
    if sampler is not None and sampler not in SAMPLERS:
        raise SceneError(f"bad sampler {sampler!r} for built-in scene '{name}': expected one of "
                         f"{', '.join(SAMPLERS)}")
    scene = BUILTIN[name](**_size(width, height))
    if sampler is not None:
        scene["sensor"]["sampler"]["type"] = sampler
    return scene


def canonical_scene_normals(scene: mi.Scene) -> mi.Scene:
    """Make a scene's computed vertex normals the same in every process (`normals`), so that the
    same seed gives the same image to the bit. Design: docs/design/canonical_normals.md.

    Args:
        scene: the loaded mi.Scene (changed in place).

    Returns:
        `scene`.
    """
    _canonical(scene)
    return scene


def load_scene(scene: Any = None, width: int | None = None, height: int | None = None,
               defines: dict[str, Any] | None = None, sampler: str | None = None) -> mi.Scene:
    """Load a scene, checked renderable, its normals canonical (module doc).

    Args:
        scene: a built-in name (None: DEFAULT), a Mitsuba XML path, a scene dict or an mi.Scene.
        width, height: a new film size (built-in scenes and XML files; an mi.Scene must match).
        defines: an XML file's `<default>` parameters, as `mitsuba -D name=value`.
        sampler: a built-in scene's sampler (`scene_dict`); files, dicts and scenes keep their
            own.

    Returns:
        The mi.Scene; an XML integrator type Mitsuba lacks is replaced, with a `SceneWarning`.

    Raises:
        SceneError: a scene that cannot be found, loaded, resized or rendered (one line).
    """
    init()
    if scene is None:
        scene = DEFAULT
    if defines and not (isinstance(scene, (str, os.PathLike)) and os.fspath(scene) not in BUILTIN):
        raise SceneError("defines apply to XML scene files (their <default> parameters) only")
    if sampler is not None and not (isinstance(scene, (str, os.PathLike))
                                    and os.fspath(scene) in BUILTIN):
        raise SceneError(f"bad sampler choice {sampler!r}: it applies to built-in scenes only; a "
                         "scene file or dict names its own (<sampler type=...>)")
    if isinstance(scene, mi.Scene):
        check_scene(scene, "the mi.Scene")
        if width or height:
            size = scene.sensors()[0].film().size()
            if (width and width != size[0]) or (height and height != size[1]):
                raise SceneError("width/height cannot change an already loaded mi.Scene; pass a "
                                 "dict or file")
        return scene
    if isinstance(scene, dict):
        if width or height:
            raise SceneError("width/height apply to built-in scenes and XML files; set the film "
                             "size in the dict")
        try:
            loaded = mi.load_dict(scene)
        except Exception as exc:  # Mitsuba raises RuntimeError with several context lines
            raise SceneError(f"cannot load scene dict: {first_line(exc)}") from None
        problem = scene_problem(loaded, "the scene dict")
        if problem is not None:
            del loaded  # see arguments.scene_problem: a refused scene must not outlive this call
            raise SceneError(problem)
        return canonical_scene_normals(loaded)
    if not isinstance(scene, (str, os.PathLike)):
        raise SceneError(f"bad scene {scene!r}: expected a built-in name "
                         f"({', '.join(sorted(BUILTIN))}), an XML path, a scene dict or an "
                         f"mi.Scene")
    name = os.fspath(scene)
    if name in BUILTIN:
        description = scene_dict(name, width, height, sampler)
        try:
            return canonical_scene_normals(mi.load_dict(description))
        except Exception as exc:
            raise SceneError(f"cannot load built-in scene '{name}': {first_line(exc)}") from None
    if not name.lower().endswith(".xml") and not os.path.exists(name):
        raise SceneError(f"unknown scene '{name}': expected a built-in scene "
                         f"({', '.join(sorted(BUILTIN))}) or a Mitsuba XML file")
    if not os.path.isfile(name):
        raise SceneError(f"scene file '{name}' does not exist")
    try:
        loaded, notes = scene_file.load_xml(name, width, height, defines)
    except SceneError:
        raise
    except Exception as exc:
        if "unused parameters" in str(exc):  # Mitsuba lists them as "- $name=value"
            unused = ", ".join(re.findall(r"\$(\w+)=", str(exc)))
            raise SceneError(f"scene file '{name}' uses no parameter {unused}: -D/defines set only "
                             f"the file's $parameters (its <default> names)") from None
        raise SceneError(f"cannot load scene file '{name}': {first_line(exc)}") from None
    problem = scene_problem(loaded, f"scene file '{name}'")
    if problem is not None:
        del loaded  # see arguments.scene_problem: a refused scene must not outlive this call
        raise SceneError(problem)
    for note in notes:
        warnings.warn(note, SceneWarning, stacklevel=2)
    return canonical_scene_normals(loaded)


class SceneWarning(UserWarning):
    """A scene was changed to render (an unknown integrator replaced); the message names what
    changed."""


def film_format(scene: mi.Scene) -> str:
    """The pixel format of the scene's film as Mitsuba develops it: the kernel computes RGB
    radiance and the film converts it (luminance Y, CIE XYZ, alpha coverage).

    Args:
        scene: the mi.Scene (its first sensor's film, read from its description).

    Returns:
        'rgb' (also where the description names none), 'rgba', 'y', 'ya', 'xyz' or 'xyza'.

    Raises:
        SceneError: a format images cannot be written in.
    """
    found = re.search(r"pixel_format\s*=\s*(\w+)", str(scene.sensors()[0].film()))
    name = found.group(1).lower() if found else "rgb"
    if name not in PIXEL_FORMATS:
        raise SceneError(f"the film's pixel format {name!r} cannot be written: expected one of "
                         f"{', '.join(sorted(set(PIXEL_FORMATS)))}")
    return name


def scene_spp(scene: mi.Scene) -> int:
    """The scene's own camera samples per pixel.

    Args:
        scene: the mi.Scene.

    Returns:
        Its first sensor's sampler's sample_count.
    """
    return int(scene.sensors()[0].sampler().sample_count())


__all__ = ["load_scene", "scene_dict", "canonical_scene_normals", "first_line", "SceneWarning",
           "film_format", "scene_spp"]
