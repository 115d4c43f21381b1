"""Loading a Mitsuba XML scene file as its author meant, with the command line's changes applied.

    scene, notes = load_xml("cbox.xml", width=64, height=48, defines={"spp": "4"})

`defines` are the file's `<default>` parameters (as `mitsuba -D`); `width`/`height` resize the
film of the first top-level sensor, includes expanded as Mitsuba expands them; an unknown
top-level integrator becomes `path` with one note. A file that needs none of this goes to
`mi.load_file` unchanged. Details: docs/design/scene_files.md.
"""
from __future__ import annotations

import os
import re
import xml.etree.ElementTree as ET
from typing import Any, Mapping

from styletrace.errors import SceneError
from styletrace.gate import mi

#: an XML comment, for `parse_xml`
COMMENT = re.compile(r"<!--.*?-->", re.S)
#: integrator properties that `stylized` shares with Mitsuba's path tracers
SHARED = ("max_depth", "rr_depth", "hide_emitters")
#: integrator types registered from Python (Mitsuba's plugin manager does not list them)
OWN = ("stylized",)


def known_integrator(kind: str) -> bool:
    """Whether Mitsuba can make an integrator of this type (ours included).

    Args:
        kind: the integrator's type name, `$parameters` substituted.

    Returns:
        False only where Mitsuba reports the plugin "not found"; its other errors count as known.
    """
    if kind in OWN or mi.PluginManager.instance().plugin_type(kind) == mi.ObjectType.Integrator:
        return True
    try:
        mi.load_dict({"type": kind})
    except Exception as exc:  # only "not found" means unknown; anything else is Mitsuba's to report
        return "not found" not in str(exc)
    return True


def substitute(text: str, params: Mapping[str, str]) -> str:
    """Replace `$parameters` as Mitsuba 3.9.1's parser does: longest name first ($ab before $a),
    plain text replacement.

    Args:
        text: the attribute's text; params: the parameters' values by name (without `$`).

    Returns:
        The text with every `$name` known replaced (unknown ones stay).
    """
    for key in sorted(params, key=len, reverse=True):
        text = text.replace("$" + key, params[key])
    return text


def add_default(params: dict[str, str], node: ET.Element) -> None:
    """Record a `<default>` as Mitsuba's parser meets it.

    Args:
        params: the parameters known so far (changed in place): a name already known (a define,
            an earlier default) keeps its value.
        node: the `<default name value>` element; its value has the known parameters substituted.
    """
    params.setdefault(node.get("name", ""), substitute(node.get("value", ""), params))


def replace_integrator(root: ET.Element, origin: str,
                       defines: Mapping[str, str] | None = None) -> str | None:
    """Swap an unknown top-level integrator for `path` with the SHARED properties, in place.

    Args:
        root: the parsed `<scene>`; origin: how the note names the file.
        defines: the file's parameters; the type is read as Mitsuba reads it, `defines` and then
            the `<default>`s before the integrator (document order) substituted.

    Returns:
        The note to show (what was kept, what dropped), or None where nothing was replaced (a
        type with an undefined `$parameter` is left to Mitsuba's parser to report).
    """
    params = {str(k): str(v) for k, v in (defines or {}).items()}
    tops = [node for node in root if node.tag == "integrator"]
    for node in root.iter():
        if node.tag == "default":
            add_default(params, node)
            continue
        if not any(node is top for top in tops):
            continue
        kind = substitute(node.get("type", ""), params)
        # "$": undefined here, Mitsuba's parser reports it
        if "$" in kind or known_integrator(kind):
            continue
        kept = [c for c in node if c.get("name") in SHARED]
        dropped = [c.get("name") or c.tag for c in node if c.get("name") not in SHARED]
        new = ET.Element("integrator", {"type": "path"})
        new.extend(kept)  # their $parameters stay: Mitsuba substitutes them in the edited text
        new.tail = node.tail
        root[list(root).index(node)] = new
        keep = ", ".join(f"{c.get('name')}={substitute(c.get('value', ''), params)}"
                         for c in kept) or "nothing"
        return (f"{origin}: integrator '{kind}' is not a Mitsuba plugin: rendering with stylized, "
                f"keeping {keep}; dropped {', '.join(dropped) or 'nothing'}")
    return None


def used_defines(defines: Mapping[str, str], before: str, after: str) -> dict[str, str]:
    """The defines to hand Mitsuba for an edited file: all but those the edit removed every use of
    (Mitsuba refuses an unused define; it was used in the file as written).

    Args:
        defines: the given defines; before, after: the file's text before and after the edit.

    Returns:
        The defines used in `after`, and those `before` never used (Mitsuba reports them).
    """
    return {k: v for k, v in defines.items() if "$" + k in after or "$" + k not in before}


#: Mitsuba's limit of nested includes (ParserConfig.max_include_depth)
MAX_INCLUDE_DEPTH = 15


def _version(node: ET.Element) -> tuple[int, ...] | None:
    try:
        return tuple(int(x) for x in node.get("version", "").split("."))
    except ValueError:
        return None


class _Includes:
    """One expansion of a scene file's includes, following Mitsuba 3.9.1's parser (parser.cpp):
    `params` the $parameters known so far (defines first, then each `<default>` met), file lookups
    on per-file resolvers, `<path>` and `<spectrum filename>` resolved as Mitsuba resolves them.
    `problem` is set when the expansion could not be faithful (the caller then refuses a resize).
    Design: docs/design/scene_files.md (include expansion).

    Args:
        defines: the given defines (they win over defaults); origin: how messages name the file.
        legacy: the scene's own version is before 2.0.
    """

    def __init__(self, defines: Mapping[str, str], origin: str, legacy: bool):
        self.params = dict(defines)
        self.origin = origin
        self.legacy = legacy          # the scene's own version is before 2.0
        self.problem: str | None = None

    def subst(self, text: str) -> str:
        return substitute(text, self.params)

    @staticmethod
    def find(name: str, folders: list[str]) -> str | None:
        """`name` looked up in `folders`, then on Mitsuba's file resolver; None where it exists
        nowhere."""
        if os.path.isabs(name):
            return name if os.path.exists(name) else None
        for folder in folders:
            candidate = os.path.join(folder, name)
            if os.path.exists(candidate):
                return os.path.abspath(candidate)
        found = str(mi.file_resolver().resolve(name))
        return os.path.abspath(found) if os.path.exists(found) else None

    def expand(self, parent: ET.Element, folder: str, resolver: list[str], depth: int) -> None:
        """Expand the includes under `parent`, an element of the file in `folder` parsed with
        `resolver` (mutated by the file's `<path>`s), `depth` includes deep."""
        i = 0
        while i < len(parent) and not self.problem:
            node = parent[i]
            if node.tag == "default":
                add_default(self.params, node)
            elif node.tag == "path" and node.get("value"):
                value = self.subst(node.get("value"))
                found = value if os.path.isabs(value) else os.path.join(folder, value)
                if not os.path.exists(found):
                    found = self.find(value, resolver) or found
                resolver.insert(0, os.path.abspath(found))
                # its effect ends with the include: nothing of it may reach the scene's text
                if depth > 0:
                    del parent[i]
                    continue
            elif node.tag == "include":
                spliced = self.included(node, folder, resolver, depth)
                if spliced is None:
                    return
                parent[i:i + 1] = spliced
                i += len(spliced)
                continue
            elif isinstance(node.tag, str):
                if node.tag == "spectrum" and node.get("filename"):
                    found = self.find(self.subst(node.get("filename")), resolver)
                    if found:
                        node.set("filename", found)
                self.expand(node, folder, resolver, depth)
            i += 1

    def included(self, node: ET.Element, folder: str, resolver: list[str],
                 depth: int) -> list[ET.Element] | None:
        name = self.subst(node.get("filename", ""))
        if depth + 1 >= MAX_INCLUDE_DEPTH:
            self.problem = (
                f"{self.origin}: <include> nests deeper than Mitsuba's limit of "
                f"{MAX_INCLUDE_DEPTH} levels at '{name}'"
            )
            return None
        lookup = [folder, *resolver]
        path = self.find(name, lookup)
        if path is None or not os.path.isfile(path):
            self.problem = f"{self.origin}: included file '{name}' not found"
            return None
        try:
            root = parse_xml(path).getroot()
        except (ET.ParseError, OSError, ValueError) as exc:
            self.problem = f"{self.origin}: included file '{path}' is not readable XML ({exc})"
            return None
        version = _version(root)
        if root.get("version") is None:
            self.problem = (f"{self.origin}: included file '{path}' has no version attribute, "
                            f"which Mitsuba requires")
            return None
        if version is None or (version < (2,)) != self.legacy:
            self.problem = (
                f"{self.origin}: included file '{path}' has version '{root.get('version')}', which "
                f"Mitsuba reads differently from the scene's"
            )
            return None
        self.expand(root, os.path.dirname(path), lookup, depth + 1)
        if self.problem:
            return None
        if root.tag == "scene":
            return list(root)
        root.attrib.pop("version", None)
        if node.get("name"):
            root.set("name", node.get("name"))
        root.tail = node.tail
        return [root]


def expand_includes(root: ET.Element, path: str,
                    defines: Mapping[str, str] | None = None) -> str | None:
    """Replace every `<include>` under `root` by what Mitsuba splices in, in place (`_Includes`).

    Args:
        root: the parsed file's root; path: the file (its folder starts the lookups).
        defines: the given defines, or None.

    Returns:
        None, or the reason the expansion cannot be faithful (root is then partly expanded and
        must not be used).
    """
    version = _version(root)
    inc = _Includes({str(k): str(v) for k, v in (defines or {}).items()}, f"scene file '{path}'",
                    legacy=version is not None and version < (2,))
    folder = os.path.dirname(os.path.abspath(path))
    inc.expand(root, folder, [folder], 0)
    return inc.problem


def has_include(root: ET.Element) -> bool:
    """Whether an element holds an `<include>` at any depth.

    Args:
        root: the element.

    Returns:
        True where `<include>` occurs under it (or is it).
    """
    return any(True for _ in root.iter("include"))


def _set_int(parent: ET.Element, name: str, value: int) -> None:
    for c in parent:
        if c.get("name") == name:
            parent.remove(c)
    parent.append(ET.Element("integer", {"name": name, "value": str(int(value))}))


def resize(root: ET.Element, width: int | None, height: int | None, origin: str) -> None:
    """Set the film size of the first top-level `<sensor>`, in place (a film is added where it has
    none: Mitsuba's default hdrfilm).

    Args:
        root: the parsed `<scene>`, includes expanded; origin: how messages name the file.
        width, height: the new size in pixels; None (or 0) keeps that side.

    Raises:
        SceneError: no top-level `<sensor>` (one behind a `<ref>` is not reached), or a film with
            a crop window.
    """
    sensor = root.find("sensor")
    if sensor is None:
        raise SceneError(
            f"cannot resize {origin}: it has no top-level <sensor> whose film could be resized "
            f"(one only reachable through a <ref> is not); edit the film's width/height in the file"
        )
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


def parse_xml(path: str) -> ET.ElementTree:
    """Parse an XML file as Mitsuba's parser reads it: that accepts a comment holding "--", which
    XML forbids (a licence header `<!-- -- SPDX ... -->`), so where parsing fails the comments are
    dropped and the text parsed again.

    Args:
        path: the XML file (UTF-8).

    Returns:
        The file's ET.ElementTree.

    Raises:
        ET.ParseError, OSError, ValueError: a file that is not XML all the same, or unreadable.
    """
    try:
        return ET.parse(path)
    except ET.ParseError:
        with open(path, encoding="utf-8") as f:
            text = COMMENT.sub("", f.read())
        return ET.ElementTree(ET.fromstring(text))


def load_xml(path: str, width: int | None = None, height: int | None = None,
         defines: Mapping[str, Any] | None = None) -> tuple[Any, list[str]]:
    """Load a Mitsuba XML scene file with the command line's changes applied.

    Args:
        path: the XML file.
        width, height: a new film size for the first top-level sensor, or None to keep it.
        defines: values of the file's `<default>` parameters, as `mitsuba -D`.

    Returns:
        (scene, notes): whatever Mitsuba made of the file, and the notes to show the user.

    Raises:
        SceneError: a resize that cannot be done correctly. Mitsuba's own errors propagate.
    """
    origin = f"scene file '{path}'"
    defines = {str(k): str(v) for k, v in (defines or {}).items()}
    try:
        tree = parse_xml(path)
    except (ET.ParseError, OSError, ValueError):
        tree = None  # leave the report to Mitsuba's parser
    notes: list[str] = []
    edited = False
    if tree is not None and tree.getroot().tag == "scene":
        root = tree.getroot()
        if has_include(root):
            # expanded on a copy: a file whose includes cannot be expanded faithfully still loads
            # through Mitsuba as it is, unless it has to be edited (resized)
            expanded = ET.fromstring(ET.tostring(root))
            problem = expand_includes(expanded, path, defines)
            if problem is None:
                root = expanded
                tree = ET.ElementTree(root)
            elif width or height:
                raise SceneError(f"cannot resize {problem}")
        before = ET.tostring(root, encoding="unicode") if defines else ""
        note = replace_integrator(root, origin, defines)
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
    return (_load_text(text, os.path.dirname(os.path.abspath(path)),
                       used_defines(defines, before, text)), notes)


__all__ = ["load_xml", "resize", "replace_integrator", "known_integrator", "expand_includes",
           "substitute", "SHARED"]
