"""Reading the `stylized` integrator's and the `styled` BSDF's properties, with one-line errors.

The same names work in XML, in Python dicts and through the CLI's `--set`.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from ..styles import StyleError, create, get
from ..styles.base import Style
from .estimation import check_estimator

PARAMETRIZATIONS = ("first_hit", "first_n_hits", "first_object_hit")
#: Properties Mitsuba's SamplingIntegrator itself reads.
BASE_KEYS = ("samples_per_pass", "timeout", "hide_emitters")
SLOT_KEYS = ("style", "inner_samples", "estimator")
OWN_KEYS = SLOT_KEYS + ("stylize", "stylize_depth", "max_depth", "rr_depth")


@dataclass
class StyleSlot:
    """A style with its inner sample counts (one per stylized level, or one for all) and estimator."""

    style: Style
    inner: tuple[int, ...]
    estimator: str = "direct"

    def n(self, level: int) -> int:
        return self.inner[min(level, len(self.inner) - 1)]


@dataclass
class Settings:
    slot: StyleSlot                 # the integrator's own style (identity: physically based)
    stylize: str = "first_hit"
    stylize_depth: int = 1
    max_depth: int = -1
    rr_depth: int = 5

    # convenience for callers that think of one style
    @property
    def style(self) -> Style:
        return self.slot.style

    @property
    def inner(self) -> tuple[int, ...]:
        return self.slot.inner


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


def parse_inner(raw: Any, default: int) -> tuple[int, ...]:
    """`inner_samples`: one count, or one per stylized level ('8,4')."""
    if raw is None:
        return (default,)
    if isinstance(raw, str):
        parts = [p for p in raw.replace(";", ",").split(",") if p.strip()]
    elif isinstance(raw, (list, tuple)):
        parts = list(raw)
    else:
        parts = [raw]
    if not parts:
        raise StyleError(f"bad value {raw!r} for 'inner_samples': expected an integer >= 1")
    return tuple(_int("inner_samples", p, 1) for p in parts)


def style_slot_from(values: dict[str, Any], context: str = "the stylized integrator",
                    extra_keys: tuple[str, ...] = ()) -> StyleSlot:
    """A style, its parameters, inner_samples and estimator from a flat mapping; unknown keys are errors."""
    values = dict(values)
    style_name = str(values.pop("style", "identity"))
    cls = get(style_name)
    style_keys = {p.name for p in cls.params}
    style_values = {k: values.pop(k) for k in list(values) if k in style_keys}
    for k in values:
        if k not in SLOT_KEYS and k not in extra_keys:
            allowed = ", ".join(sorted(style_keys)) or "none"
            own = ", ".join(k2 for k2 in SLOT_KEYS + extra_keys if k2 not in BASE_KEYS)
            raise StyleError(f"unknown property '{k}' for {context} with style '{style_name}': "
                             f"the style's parameters are {allowed}; the others are {own}")
    style = create(style_name, **style_values)
    inner = parse_inner(values.get("inner_samples"), max(style.default_inner, 1))
    estimator = str(values.get("estimator", "direct"))
    check_estimator(estimator, style)
    return StyleSlot(style=style, inner=inner, estimator=estimator)


def settings_from(values: dict[str, Any]) -> Settings:
    """Validated integrator settings from a flat name -> value mapping (property values or CLI strings)."""
    if str(values.get("hide_emitters", False)).lower() in ("true", "1"):
        raise StyleError("bad value True for 'hide_emitters': the stylized integrator does not support hiding "
                         "emitters (their emission is part of the stylized radiance)")
    slot = style_slot_from(values, extra_keys=OWN_KEYS[len(SLOT_KEYS):] + BASE_KEYS)
    stylize = str(values.get("stylize", "first_hit"))
    if stylize not in PARAMETRIZATIONS:
        raise StyleError(f"bad value {stylize!r} for 'stylize': expected one of {', '.join(PARAMETRIZATIONS)}")
    depth = _int("stylize_depth", values.get("stylize_depth", 1), 1)
    if stylize == "first_hit" and depth != 1:
        raise StyleError(f"bad value {depth!r} for 'stylize_depth': 'first_hit' stylizes one level; "
                         f"use stylize=first_n_hits or first_object_hit for more")
    if stylize == "first_object_hit" and slot.style.name != "identity":
        raise StyleError(f"bad value {slot.style.name!r} for 'style': with stylize=first_object_hit the styles "
                         f"come from 'styled' BSDFs, so the integrator's own style must be identity")
    if len(slot.inner) not in (1, depth):
        expected = "1 count (one stylized level)" if depth == 1 else f"1 or {depth} counts (one per stylized level)"
        raise StyleError(f"bad value {values.get('inner_samples')!r} for 'inner_samples': expected {expected}")
    max_depth = _int("max_depth", values.get("max_depth", -1), -1)
    if max_depth == 0:
        raise StyleError("bad value 0 for 'max_depth': expected -1 (unbounded) or an integer >= 1")
    rr_depth = _int("rr_depth", values.get("rr_depth", 5), 1)
    return Settings(slot=slot, stylize=stylize, stylize_depth=depth, max_depth=max_depth, rr_depth=rr_depth)


def props_to_dict(props) -> dict[str, Any]:
    """mi.Properties -> plain dict (reading marks each entry as used; we validate them ourselves)."""
    return {key: props[key] for key in props.keys()}
