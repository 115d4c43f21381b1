"""Loading a Mitsuba XML scene file as its author meant, with the command line's changes applied.

    scene, notes = load("cbox.xml", width=64, height=48, defines={"spp": "4"})

- `defines` are the values of the file's `<default>` parameters (`$name`), as `mitsuba -D name=value`;
  Mitsuba refuses a name the file does not use.
- `width`/`height` resize the film of the first top-level `<sensor>`: the XML is parsed (xml.etree), the
  film's `width`/`height` are set (a film is added where the sensor has none: Mitsuba's default hdrfilm),
  and the edited text is loaded with the file's folder first on Mitsuba's file resolver, so relative
  paths resolve as before. A film with a crop window, or a sensor only reachable through `<include>` or
  `<ref>`, is refused in one line rather than resized wrongly.
- A top-level `<integrator>` whose type Mitsuba does not know (a scene written for another implementation
  of stylized rendering, say `type="sre"`) is replaced by a `path` integrator that keeps its `max_depth`,
  `rr_depth` and `hide_emitters`; the front ends then render it with `stylized`, which carries those over
  (`api.carried_settings`). One note names what was dropped.

A file that needs none of this is handed to `mi.load_file` unchanged.
"""
from __future__ import annotations

import os
import xml.etree.ElementTree as ET
from typing import Any, Mapping

import mitsuba as mi

from .errors import SceneError

#: integrator properties that `stylized` shares with Mitsuba's path tracers
SHARED = ("max_depth", "rr_depth", "hide_emitters")
#: integrator types registered from Python (Mitsuba's plugin manager does not list them)
OWN = ("stylized",)


def known_integrator(kind: str) -> bool:
    if kind in OWN or mi.PluginManager.instance().plugin_type(kind) == mi.ObjectType.Integrator:
        return True
    try:
        mi.load_dict({"type": kind})
    except Exception as exc:  # only "not found" means unknown; anything else is Mitsuba's to report
        return "not found" not in str(exc)
    return True


def replace_integrator(root: ET.Element, origin: str) -> str | None:
    """Swap an unknown top-level integrator for `path` with the shared depths; the note to show, or None."""
    for i, node in enumerate(list(root)):
        if node.tag != "integrator" or known_integrator(node.get("type", "")):
            continue
        kept = [c for c in node if c.get("name") in SHARED]
        dropped = [c.get("name") or c.tag for c in node if c.get("name") not in SHARED]
        new = ET.Element("integrator", {"type": "path"})
        new.extend(kept)
        new.tail = node.tail
        root[i] = new
        keep = ", ".join(f"{c.get('name')}={c.get('value')}" for c in kept) or "nothing"
        return (f"{origin}: integrator '{node.get('type')}' is not a Mitsuba plugin: rendering with stylized, "
                f"keeping {keep}; dropped {', '.join(dropped) or 'nothing'}")
    return None


def _set_int(parent: ET.Element, name: str, value: int) -> None:
    for c in parent:
        if c.get("name") == name:
            parent.remove(c)
    parent.append(ET.Element("integer", {"name": name, "value": str(int(value))}))


def resize(root: ET.Element, width: int | None, height: int | None, origin: str) -> None:
    sensor = root.find("sensor")
    if sensor is None:
        raise SceneError(f"cannot resize {origin}: it has no top-level <sensor> whose film could be resized "
                         f"(one in an <include> or <ref> is not); edit the film's width/height in the file")
    film = sensor.find("film")
    if film is None:  # Mitsuba's default film
        film = ET.SubElement(sensor, "film", {"type": "hdrfilm"})
    crop = sorted(c.get("name") for c in film if str(c.get("name", "")).startswith("crop_"))
    if crop:
        raise SceneError(f"cannot resize {origin}: its film has a crop window ({', '.join(crop)}); "
                         f"render it at its own size")
    for name, value in (("width", width), ("height", height)):
        if value:
            _set_int(film, name, value)


def _load_text(text: str, folder: str, defines: Mapping[str, str]) -> mi.Scene:
    resolver = mi.file_resolver()
    before = list(resolver)
    resolver.prepend(folder)
    try:
        return mi.load_string(text, **defines)
    finally:
        resolver.clear()
        for p in before:
            resolver.append(p)


def load(path: str, width: int | None = None, height: int | None = None,
         defines: Mapping[str, Any] | None = None) -> tuple[Any, list[str]]:
    """The loaded file (whatever Mitsuba made of it) and the notes to show the user. Mitsuba's own
    errors propagate; the caller turns them into one line."""
    origin = f"scene file '{path}'"
    defines = {str(k): str(v) for k, v in (defines or {}).items()}
    try:
        tree = ET.parse(path)
    except (ET.ParseError, OSError, ValueError):
        tree = None  # leave the report to Mitsuba's parser
    notes: list[str] = []
    edited = False
    if tree is not None and tree.getroot().tag == "scene":
        root = tree.getroot()
        note = replace_integrator(root, origin)
        if note:
            notes.append(note)
            edited = True
        if width or height:
            resize(root, width, height, origin)
            edited = True
    elif width or height:
        raise SceneError(f"cannot resize {origin}: it is not a readable <scene> XML file")
    if not edited:
        return mi.load_file(path, **defines), notes
    text = ET.tostring(tree.getroot(), encoding="unicode")
    return _load_text(text, os.path.dirname(os.path.abspath(path)), defines), notes


__all__ = ["load", "resize", "replace_integrator", "known_integrator", "SHARED"]
