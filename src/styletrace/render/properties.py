"""Reading the `stylized` integrator's properties, with one-line errors for bad values.

The same names work in XML, in Python dicts and through the CLI's `--set`.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

from ..styles import StyleError, create, get
from ..styles.base import Style
from .estimation import build_estimator

PARAMETRIZATIONS = ("first_hit", "first_n_hits")
#: Properties Mitsuba's SamplingIntegrator itself reads.
BASE_KEYS = ("samples_per_pass", "timeout", "hide_emitters")
OWN_KEYS = ("style", "inner_samples", "estimator", "stylize", "stylize_depth", "max_depth", "rr_depth")


@dataclass
class Settings:
    style: Style
    inner: tuple[int, ...]          # inner sample count per stylized level
    estimator: str = "direct"
    stylize: str = "first_hit"
    stylize_depth: int = 1
    max_depth: int = -1
    rr_depth: int = 5
    estimators: list = field(default_factory=list)  # one per stylized level


def _int(key: str, raw: Any, low: int) -> int:
    try:
        if isinstance(raw, float) and not raw.is_integer():
            raise ValueError
        value = int(raw) if not isinstance(raw, str) else int(raw.strip())
    except (TypeError, ValueError):
        raise StyleError(f"bad value {raw!r} for '{key}': expected an integer >= {low}") from None
    if value < low:
        raise StyleError(f"bad value {raw!r} for '{key}': expected an integer >= {low}")
    return value


def parse_inner(raw: Any, levels: int, default: int) -> tuple[int, ...]:
    """`inner_samples`: one count, or one per stylized level ('8,4'); a single count serves every level."""
    if raw is None:
        return (default,) * levels
    if isinstance(raw, str):
        parts = [p for p in raw.replace(";", ",").split(",") if p.strip()]
    elif isinstance(raw, (list, tuple)):
        parts = list(raw)
    else:
        parts = [raw]
    counts = tuple(_int("inner_samples", p, 1) for p in parts)
    if len(counts) == 1:
        return counts * levels
    if len(counts) != levels:
        raise StyleError(f"bad value {raw!r} for 'inner_samples': expected 1 or {levels} counts "
                         f"(one per stylized level)")
    return counts


def settings_from(values: dict[str, Any]) -> Settings:
    """Build validated settings from a flat name -> value mapping (property values or CLI strings)."""
    values = dict(values)
    style_name = str(values.pop("style", "identity"))
    cls = get(style_name)
    style_keys = {p.name for p in cls.params}
    style_values = {k: values.pop(k) for k in list(values) if k in style_keys}
    for k in list(values):
        if k not in OWN_KEYS and k not in BASE_KEYS:
            allowed = ", ".join(sorted(style_keys)) or "none"
            raise StyleError(f"unknown property '{k}' for the stylized integrator with style '{style_name}': "
                             f"the style's parameters are {allowed}; the integrator's are {', '.join(OWN_KEYS)}")
    style = create(style_name, **style_values)

    stylize = str(values.get("stylize", "first_hit"))
    if stylize not in PARAMETRIZATIONS:
        raise StyleError(f"bad value {stylize!r} for 'stylize': expected one of {', '.join(PARAMETRIZATIONS)}")
    depth = _int("stylize_depth", values.get("stylize_depth", 1), 1)
    if stylize == "first_hit" and depth != 1:
        raise StyleError(f"bad value {depth!r} for 'stylize_depth': 'first_hit' stylizes one level; "
                         f"use stylize=first_n_hits for more")
    default_inner = max(style.default_inner, 1)
    inner = parse_inner(values.get("inner_samples"), depth, default_inner)
    estimator = str(values.get("estimator", "direct"))
    max_depth = _int("max_depth", values.get("max_depth", -1), -1)
    if max_depth == 0:
        raise StyleError("bad value 0 for 'max_depth': expected -1 (unbounded) or an integer >= 1")
    rr_depth = _int("rr_depth", values.get("rr_depth", 5), 1)
    estimators = [build_estimator(estimator, style, n) for n in inner]
    return Settings(style=style, inner=inner, estimator=estimator, stylize=stylize, stylize_depth=depth,
                    max_depth=max_depth, rr_depth=rr_depth, estimators=estimators)


def props_to_dict(props) -> dict[str, Any]:
    """mi.Properties -> plain dict, marking every entry as read (we validate them ourselves)."""
    out = {}
    for key in props.keys():
        out[key] = props[key]
    return out
