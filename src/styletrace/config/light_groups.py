"""Light groups: the `light_groups` property, the style slot of each group, and the mark that puts
an emitter in a group.

    groups = parse_groups(values, parse_slot, default_slot)  # () where light_groups is unset
    group_mark("sun__lg_key")                                # 'key' ('' without a mark)

`light_groups="key:cel;fill:identity"` names the groups and their styles; `<group>.<key>` values
(`key.levels`, `key.estimator`, `key.inner_samples`) give a group's style parameters, estimator
and children, as `style`'s companions give the integrator's (children: the integrator's count
unless given). An emitter joins a group by a mark
in its id (`__lg_<group>`), or an area light by the mark in its shape's id: Mitsuba refuses a
property it does not know on its own emitters. The unmarked light is the group `default`, which
takes the integrator's own style. Docs: docs/light_groups.md.
"""
from __future__ import annotations

import re
from dataclasses import dataclass
from typing import Any, Callable, Mapping

from styletrace.errors import SettingsError

#: the group of the light no mark claims; its style is the integrator's own
DEFAULT = "default"
#: a group's name: a letter, then letters and digits (it sits in ids between `__` marks)
NAME = re.compile(r"[A-Za-z][A-Za-z0-9]*$")
#: an emitter's (or its shape's) mark, followed by the end of the id or by another mark
MARK = re.compile(r"__lg_([A-Za-z][A-Za-z0-9]*)(?=__|$)")


@dataclass(frozen=True)
class LightGroup:
    """One group: its name and the style slot (style, children, estimator) applied to its light."""

    name: str
    slot: Any  # settings.StyleSlot


def group_mark(ident: str | None) -> str:
    """The group an id's mark names.

    Args:
        ident: an emitter's or a shape's id (None or '' for none).

    Returns:
        The group's name, or '' where the id carries no mark.
    """
    m = MARK.search(ident or "")
    return m.group(1) if m else ""


def group_keys(values: Mapping[str, Any]) -> list[str]:
    """The `<group>.<key>` names among property values: the names with a dot whose part before
    it is a group `light_groups` declares (other dotted names are the style's own: a composed
    style's `contrast.c`).

    Args:
        values: property name -> raw value.

    Returns:
        The names, in the mapping's order.

    Raises:
        SettingsError: a bad `light_groups` spec.
    """
    names = {n for n, _ in _spec(values.get("light_groups"))}
    return [k for k in values if isinstance(k, str) and k.split(".", 1)[0] in names]


def _spec(raw: Any) -> list[tuple[str, str]]:
    """[(group, style name)] from 'name:style;name:style', each group once, never `default`."""
    if raw is None or (isinstance(raw, str) and not raw.strip()):
        return []
    if not isinstance(raw, str):
        raise SettingsError(f"bad value {raw!r} for 'light_groups': expected a string "
                            "'name:style;name:style'")
    out = []
    for part in (p.strip() for p in raw.split(";")):
        if not part:
            continue
        name, sep, style = (s.strip() for s in part.partition(":"))
        if not sep or not style:
            raise SettingsError(f"bad value {part!r} in 'light_groups': expected name:style "
                                "(e.g. key:cel)")
        if not NAME.match(name) or name == DEFAULT:
            raise SettingsError(f"bad group name {name!r} in 'light_groups': expected a letter "
                                f"then letters and digits, not {DEFAULT!r} (the unmarked light, "
                                "styled by the integrator's style)")
        if any(name == n for n, _ in out):
            raise SettingsError(f"bad value {raw!r} for 'light_groups': group {name!r} is named "
                                "twice")
        out.append((name, style))
    return out


def parse_groups(values: Mapping[str, Any], parse_slot: Callable, default_slot) -> tuple:
    """The groups of `values`: `default` with the integrator's slot first, then those of
    `light_groups` in their order, each with its `<group>.<key>` values; () where none is named.

    Args:
        values: property name -> raw value (`light_groups` and the `<group>.<key>` names).
        parse_slot: `settings.parse_slot` (passed in: settings imports this module).
        default_slot: the integrator's own parsed slot.

    Returns:
        tuple[LightGroup, ...].

    Raises:
        SettingsError: a bad spec (a `<name>.<key>` of no declared group is the style's, which
            refuses a key it does not know).
        StyleError: an unknown style or a bad value of its parameters.
    """
    spec = _spec(values.get("light_groups"))
    if not spec:
        return ()
    groups = [LightGroup(DEFAULT, default_slot)]
    for name, style in spec:
        prefix = name + "."
        own = {k[len(prefix):]: v for k, v in values.items()
               if isinstance(k, str) and k.startswith(prefix)}
        # the children are shared: by default a group takes as many as the integrator's style
        own.setdefault("inner_samples", list(default_slot.inner))
        slot = parse_slot({"style": style, **own}, context=f"light group {name!r}")
        groups.append(LightGroup(name, slot))
    return tuple(groups)


def check_supported(groups: tuple, settings) -> None:
    """Refuse what light groups do not support yet (docs/light_groups.md): every stylize mode but
    first_hit, reuse, lines, error AOVs, the expansion pass, firefly control, adaptive counts,
    closed-form styles and estimators whose children follow a comb.

    Args:
        groups: the parsed groups (() : nothing to check). settings: the parsed `Settings`.

    Raises:
        SettingsError: one line naming the setting and what is allowed.
    """
    if not groups:
        return
    s = settings
    for key, bad, allowed in (
        ("stylize", s.stylize != "first_hit" and repr(s.stylize), "first_hit"),
        ("reuse", s.reuse != "off" and repr(s.reuse), "off"),
        ("lines", s.lines is not None and "True", "False"),
        ("aovs", s.aovs and "True", "False (each group's Combined is an AOV of its own)"),
        ("expansion_pass", s.expansion_pass and str(s.expansion_pass), "0"),
        ("firefly", bool(s.extra.get("firefly")) and str(s.extra.get("firefly")), "0 or auto"),
    ):
        if bad:
            raise SettingsError(f"bad value {bad} for {key!r} with light_groups: not yet "
                                f"supported with light groups; use {allowed}")
    for g in groups:
        slot = g.slot
        if slot.style.closed_form:
            raise SettingsError(f"bad style {slot.style.name!r} for light group {g.name!r}: a "
                                "closed-form style reads no light; use a style of expectation")
        if any(hasattr(n, "n_max") for n in slot.inner):
            raise SettingsError(f"bad value {list(slot.inner)!r} for 'inner_samples' of light "
                                f"group {g.name!r}: adaptive counts are not yet supported with "
                                "light groups; use a fixed count")


__all__ = ["DEFAULT", "check_supported", "LightGroup", "group_mark", "group_keys", "parse_groups"]
