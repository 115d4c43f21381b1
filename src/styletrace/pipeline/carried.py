"""The settings a scene's own Mitsuba integrator shares with `stylized`: max_depth, rr_depth,
hide_emitters.

    carried = carried_settings(scene, source="scene.xml", defines={"depth": "3"})  # {max_depth: 3}

Two sources: the declaration (read with Mitsuba's own parser, $parameters resolved with the same
defines; it sees through the `moment` and `aov` wrappers) and the loaded object (the values Mitsuba
resolved, defaults included). What is declared wins; the object fills in the rest. `direct` is
max_depth 2. A `stylized` integrator carries nothing: its own values are the base
(`nested_stylized` reads them from the declaration when it is wrapped).
Design: docs/design/carried_settings.md.
"""
from __future__ import annotations

import os
import re
from typing import Any, Mapping

from styletrace.gate import mi

#: integrator properties that `stylized` shares with Mitsuba's path tracers
SHARED = ("max_depth", "rr_depth", "hide_emitters")
#: integrators that render through the integrators nested in them (Mitsuba's `moment` and `aov`)
WRAPPERS = ("moment", "aov")
#: Mitsuba stores max_depth -1 (unbounded) as a UInt32
UNBOUNDED = 2 ** 32 - 1


def _depth(value: Any) -> int:
    value = int(value)
    return -1 if value >= UNBOUNDED else value


def rendering_node(state, node):
    """The integrator node that renders: `node`, or through wrappers the first one nested in it.

    Args:
        state: the parser state of `mitsuba.parser` (its `nodes`).
        node: an integrator node of that state.

    Returns:
        `node` unless it is a wrapper (`WRAPPERS`); else the first integrator nested in it, followed
        through further wrappers (a wrapper that nests none: that wrapper).
    """
    seen = set()
    while node.props.plugin_name() in WRAPPERS and id(node) not in seen:
        seen.add(id(node))
        inner = [state.nodes[node.props[k].index()] for k in node.props.keys()
                 if type(node.props[k]).__name__ == "ResolvedReference"]
        inner = [n for n in inner if n.type == mi.ObjectType.Integrator]
        if not inner:
            break
        node = inner[0]
    return node


def _rendering_node(source: Any, defines: Mapping[str, Any] | None):
    """(the scene's top integrator node, the node that renders) as Mitsuba's parser reads the
    source; None where the source cannot be read this way (an mi.Scene) or declares no
    integrator."""
    import mitsuba.parser as parser
    config = parser.ParserConfig(mi.variant())
    try:
        if isinstance(source, dict):
            state = parser.parse_dict(config, source)
        elif isinstance(source, (str, os.PathLike)) and os.path.isfile(source):
            state = parser.parse_file(
                config, os.fspath(source), **{k: str(v) for k, v in (defines or {}).items()}
            )
        else:
            return None
    # the loader reports a broken scene in its own words; here it only means "unknown"
    except Exception:
        return None
    root = state.nodes[0]
    tops = [state.nodes[root.props[k].index()] for k in root.props.keys()
            if type(root.props[k]).__name__ == "ResolvedReference"]
    tops = [n for n in tops if n.type == mi.ObjectType.Integrator]
    if not tops:
        return None
    return tops[0], rendering_node(state, tops[0])


def declared(source: Any, defines: Mapping[str, Any] | None = None) -> dict[str, Any] | None:
    """The shared settings the scene source declares for the integrator that renders, plus its type.

    Args:
        source: a scene dict or the path of an XML file (anything else: None).
        defines: values of the XML file's `<default>` parameters, as Mitsuba's -D.

    Returns:
        {"type": its plugin name, and the SHARED keys declared} (a depth -1 for unbounded); None
        where the source cannot be read this way (an mi.Scene, a broken file) or declares no
        integrator.
    """
    nodes = _rendering_node(source, defines)
    if nodes is None:
        return None
    props = nodes[1].props
    out: dict[str, Any] = {"type": props.plugin_name()}
    for key in SHARED:
        if key in props.keys():
            out[key] = bool(props[key]) if key == "hide_emitters" else _depth(props[key])
    return out


def nested_stylized(source: Any, defines: Mapping[str, Any] | None = None) -> dict[str, Any] | None:
    """The property values of a `stylized` integrator nested in a wrapper (`moment`, `aov`).

    Args:
        source: a scene dict or the path of an XML file.
        defines: values of the XML file's `<default>` parameters.

    Returns:
        Its property values as the declaration gives them; None for none (no wrapper, another
        integrator, a source that cannot be read this way such as an mi.Scene).
    """
    nodes = _rendering_node(source, defines)
    if nodes is None or nodes[0] is nodes[1] or nodes[1].props.plugin_name() != "stylized":
        return None
    props = nodes[1].props
    return {key: props[key] for key in props.keys()}


def loaded(integrator: mi.Integrator) -> dict[str, Any]:
    """The shared settings as a loaded Mitsuba integrator reports them (see the module doc).

    Args:
        integrator: the loaded integrator (not `stylized`).

    Returns:
        max_depth and rr_depth from its attributes (Python integrators) or its description (C++
        ones; `direct`: max_depth 2), hide_emitters only where True; the rest left out.
    """
    out: dict[str, Any] = {}
    text = str(integrator)
    for key in ("max_depth", "rr_depth"):
        value = getattr(integrator, key, None)
        if isinstance(value, int) and not isinstance(value, bool):
            out[key] = _depth(value)
            continue
        # C++ integrators: their description only
        found = re.search(rf"\b{key}\s*=\s*(-?\d+)", text)
        if found:
            out[key] = _depth(found.group(1))
    if text.startswith("DirectIntegrator"):
        out["max_depth"] = 2
    if getattr(integrator, "hide_emitters", False):  # absent on adjoint integrators (ptracer)
        out["hide_emitters"] = True
    return out


def carried_settings(
    scene: mi.Scene, source: Any = None, defines: Mapping[str, Any] | None = None
) -> dict[str, Any]:
    """max_depth, rr_depth and hide_emitters of the scene's own (non-`stylized`) integrator.

    Args:
        scene: the loaded scene.
        source, defines: what the scene was loaded from, to read its declaration (None: the loaded
            object alone).

    Returns:
        The declared values over the loaded object's (`direct`: max_depth 2), hide_emitters only
        where True; {} for no integrator or a `stylized` one.
    """
    from styletrace.kernel.integrator import StylizedIntegrator
    own = scene.integrator()
    if own is None or isinstance(own, StylizedIntegrator):
        return {}
    out = loaded(own)
    decl = declared(source, defines) if source is not None else None
    if decl is not None and decl.get("type") != "stylized":
        if decl["type"] == "direct":
            # emission plus direct light, whatever max_depth it declares; also nested in `moment` or
            # `aov`, whose loaded object reports no depth of it
            decl["max_depth"] = 2
        out.update({k: v for k, v in decl.items() if k in SHARED})
    if out.get("hide_emitters") is False:
        del out["hide_emitters"]
    return out


__all__ = ["carried_settings", "declared", "nested_stylized", "loaded", "SHARED", "WRAPPERS"]
