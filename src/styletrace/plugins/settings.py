"""The `stylized` integrator's settings: their names, defaults, parsing, docs and refinement, in one place.

Every front end goes through here: Mitsuba properties (XML, dicts), the command line's flags and
`--set`, and the Python API's keywords. A mapping of property values is parsed once into `Settings`;
bad values raise `SettingsError` (or `StyleError` for the style's own parameters) with one line.
The integrator's property table in the README and the docs is generated from `PROPERTIES`.

    settings = parse({"style": "cel", "inner_samples": "8,4", "stylize": "first_n_hits", "stylize_depth": 2})
    values = refine(scene_integrator.values, {"inner_samples": 16})   # a scene's own integrator, refined
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Mapping

from ..errors import SettingsError
from ..styles import create, get
from ..styles.base import Style
from . import estimation
from .emitter_sampler import DEFAULT_MODE as EMITTER_DEFAULT, MODES as EMITTER_MODES


@dataclass(frozen=True)
class Property:
    """One integrator property: its default, its type as the docs show it, its flag and its doc line."""

    name: str
    default: Any
    kind: str
    doc: str
    flag: str = ""            # the `styletrace render` flag, if it has its own
    metavar: str = ""

    def show_default(self) -> str:
        return "style's" if self.default is None else str(self.default)


STYLIZE_MODES = {
    "first_hit": "the camera ray's first hit; objects with a `styled` BSDF use their own style",
    "first_n_hits": "the first N vertices of every path, recursively",
    "first_object_hit": "the first vertex on a styled object at any depth (through mirrors and glass)",
}

REUSE_MODES = {
    "off": "every camera sample uses its own children (the tree sampler)",
    "pixels": "first_hit only: pool the children of neighbouring pixels' first hits (docs/reuse.md)",
}
REUSE_WEIGHTS = ("balance", "pairwise")
#: Largest pixel window half-size for reuse=pixels (a 17 x 17 window).
MAX_REUSE_RADIUS = 8
#: Most neighbours a pool holds: the kernel keeps a pool as one bit per neighbour (and one for the vertex
#: itself) in a UInt64, and the cost grows as (K+1)^2 (every pooled sample's mixture density sums K+1 terms).
MAX_REUSE_K = 63

PROPERTIES = (
    Property("style", "identity", "string", "registry name of the style (`styletrace styles`)", "--style", "NAME"),
    Property("inner_samples", None, "int or list", "n: child estimates per stylized vertex; `8,4` sets one per "
             "level", "--inner", "N"),
    Property("estimator", "direct", "string", "how g(E[L]) is estimated from the children: "
             + ", ".join(estimation.names()), "--estimator", "NAME"),
    Property("stylize", "first_hit", "string", "where styles apply: " + ", ".join(STYLIZE_MODES), "--stylize",
             "MODE"),
    Property("stylize_depth", 1, "int", "N, the number of stylized levels (at most 8: tracing time doubles "
             "per level)", "--stylize-depth", "N"),
    Property("max_depth", -1, "int", "longest path, as Mitsuba's `path` (-1: unbounded)", "--max-depth", "D"),
    Property("emitter_sampling", EMITTER_DEFAULT, "string", "how next-event estimation picks a light: uniform (as "
             "Mitsuba) or power (by estimated emitted power: better with lights of very different strengths, worse "
             "where a sky dominates the estimate; BENCHMARKS.md)", "--emitter-sampling", "MODE"),
    Property("rr_depth", 5, "int", "depth at which Russian roulette starts, as Mitsuba's `path`", "--rr-depth", "D"),
    Property("hide_emitters", False, "bool", "camera rays do not see emitters, as Mitsuba's `path`: they pass "
             "through area lights and find black (alpha 0) where they escape", "--hide-emitters", "BOOL"),
    Property("reuse", "off", "string", "sample reuse at the stylized vertex: " + ", ".join(REUSE_MODES)
             + " (Tong and Hachisuka 2025; docs/reuse.md)", "--reuse", "MODE"),
    Property("reuse_radius", 2, "int", f"reuse=pixels: half-size r of the pixel window the neighbours come from "
             f"((2r+1) x (2r+1), r at most {MAX_REUSE_RADIUS})", "--reuse-radius", "R"),
    Property("reuse_k", 8, "int", "reuse=pixels: neighbours pooled per camera sample, drawn from the window "
             f"(at most (2r+1)^2 - 1 and {MAX_REUSE_K})", "--reuse-k", "K"),
    Property("reuse_mis", "balance", "string", "reuse=pixels: weights of the pooled BSDF samples: balance (the "
             "mixture density of the whole pool, (K+1)^2 density evaluations) or pairwise (each neighbour against "
             "the vertex itself, 2K+1; docs/reuse.md)", "--reuse-mis", "NAME"),
)
DEFAULTS = {p.name: p.default for p in PROPERTIES}
#: the style `styletrace render` uses on a scene without a `stylized` integrator of its own
COMMAND_LINE_STYLE = "cel"
#: what a `styled` BSDF accepts besides its style's parameters
SLOT_KEYS = ("style", "inner_samples", "estimator")
#: properties Mitsuba's SamplingIntegrator reads itself
BASE_KEYS = ("samples_per_pass", "timeout")
#: Largest depth or count: the kernel counts depths and samples in UInt32, and 2^32 - 1 stands for
#: "unbounded" (`path.depth_limit`), so larger values would wrap around.
COUNT_MAX = 2 ** 32 - 2
#: Most stylized levels for first_n_hits/first_object_hit. Each level's loop is traced inside the draw of
#: the one above, and Dr.Jit traces a symbolic loop's body twice (JitFlag.OptimizeLoops), so the trace time
#: doubles per level (measured, 8x8 Cornell box, inner 1: 3.3 s at 8 levels, 10 s at 10, 21 s at 11, 52 s
#: at 12; 1000 levels overflow Python's recursion). Deeper trees are refused rather than left to hang.
MAX_STYLIZE_DEPTH = 8


@dataclass(frozen=True)
class StyleSlot:
    """A style with its inner sample counts (one per stylized level, or one for all) and estimator."""

    style: Style
    inner: tuple[int, ...]
    estimator: str = "direct"

    def n(self, level: int) -> int:
        return self.inner[min(level, len(self.inner) - 1)]


@dataclass(frozen=True)
class Settings:
    slot: StyleSlot                 # the integrator's own style (identity: physically based)
    stylize: str = "first_hit"
    stylize_depth: int = 1
    max_depth: int = -1
    rr_depth: int = 5
    emitter_sampling: str = EMITTER_DEFAULT
    hide_emitters: bool = False
    reuse: str = "off"
    reuse_radius: int = 2
    reuse_k: int = 8
    reuse_mis: str = "balance"

    @property
    def style(self) -> Style:
        return self.slot.style

    @property
    def inner(self) -> tuple[int, ...]:
        return self.slot.inner

    def describe(self) -> str:
        return (f"style={self.style.describe()}, inner={list(self.inner)}, estimator={self.slot.estimator}, "
                f"stylize={self.stylize}, stylize_depth={self.stylize_depth}, max_depth={self.max_depth}"
                + (f", reuse={self.reuse}(r={self.reuse_radius}, k={self.reuse_k}, {self.reuse_mis})" if self.reuse != "off" else ""))


def integer(key: str, raw: Any, low: int, high: int = COUNT_MAX) -> int:
    """An integer in [low, high] from a number or a string; exact (1.5 and '2.7' are refused, not truncated)."""
    expected = f"expected an integer in [{low}, {high}]"
    try:
        if isinstance(raw, bool):
            raise ValueError
        if isinstance(raw, float) and not raw.is_integer():
            raise ValueError
        value = int(raw.strip()) if isinstance(raw, str) else int(raw)
    except (TypeError, ValueError, OverflowError):
        raise SettingsError(f"bad value {raw!r} for '{key}': {expected}") from None
    if not low <= value <= high:
        raise SettingsError(f"bad value {raw!r} for '{key}': {expected}")
    return value


def boolean(key: str, raw: Any) -> bool:
    """A bool from True/False, 1/0 or the strings 'true'/'false'/'1'/'0' (any case)."""
    text = str(raw).strip().lower()
    if isinstance(raw, bool) or text in ("true", "false", "1", "0") and not isinstance(raw, float):
        return text in ("true", "1")
    raise SettingsError(f"bad value {raw!r} for '{key}': expected true or false")


def parse_inner(raw: Any, default: int) -> tuple[int, ...]:
    """`inner_samples`: one count, or one per stylized level ('8,4', [8, 4] or (8, 4))."""
    if raw is None:
        return (default,)
    if isinstance(raw, str):
        parts = [p for p in raw.replace(";", ",").split(",") if p.strip()]
    elif isinstance(raw, (list, tuple)):
        parts = list(raw)
    else:
        parts = [raw]
    if not parts:
        raise SettingsError(f"bad value {raw!r} for 'inner_samples': expected an integer in [1, {COUNT_MAX}]")
    return tuple(integer("inner_samples", p, 1) for p in parts)


def parse_slot(values: Mapping[str, Any], context: str = "the stylized integrator",
               extra_keys: tuple[str, ...] = ()) -> StyleSlot:
    """A style, its parameters, inner_samples and estimator from a flat mapping; unknown keys are errors."""
    values = dict(values)
    style_name = str(values.pop("style", DEFAULTS["style"]))
    cls = get(style_name)
    style_keys = {p.name for p in cls.params}
    style_values = {k: values.pop(k) for k in list(values) if k in style_keys}
    for k in values:
        if k not in SLOT_KEYS and k not in extra_keys:
            allowed = ", ".join(sorted(style_keys)) or "none"
            own = ", ".join(k2 for k2 in SLOT_KEYS + extra_keys if k2 not in BASE_KEYS)
            raise SettingsError(f"unknown property '{k}' for {context} with style '{style_name}': "
                                f"the style's parameters are {allowed}; the others are {own}")
    style = create(style_name, **style_values)
    inner = parse_inner(values.get("inner_samples"), max(style.default_inner, 1))
    name = str(values.get("estimator", DEFAULTS["estimator"]))
    return StyleSlot(style=style, inner=inner, estimator=estimation.check(name, style))


def parse(values: Mapping[str, Any]) -> Settings:
    """Validated integrator settings from a flat name -> value mapping (property values, CLI strings or
    Python values); missing names take DEFAULTS."""
    if "samples_per_pass" in values:
        raise SettingsError(f"bad value {values['samples_per_pass']!r} for 'samples_per_pass': the stylized "
                            f"integrator renders in styletrace's own passes; set the samples per pass with "
                            f"`--pass-spp` (command line) or passes(lanes_per_pass=...) (Python) instead")
    own = tuple(p.name for p in PROPERTIES if p.name not in SLOT_KEYS)
    slot = parse_slot(values, extra_keys=own + BASE_KEYS)
    get_ = lambda key: values.get(key, DEFAULTS[key])  # noqa: E731
    stylize = str(get_("stylize"))
    if stylize not in STYLIZE_MODES:
        raise SettingsError(f"bad value {stylize!r} for 'stylize': expected one of {', '.join(STYLIZE_MODES)}")
    depth = integer("stylize_depth", get_("stylize_depth"), 1, MAX_STYLIZE_DEPTH)
    if stylize == "first_hit" and depth != 1:
        raise SettingsError(f"bad value {depth!r} for 'stylize_depth': 'first_hit' stylizes one level; "
                            f"use stylize=first_n_hits or first_object_hit for more")
    if stylize == "first_object_hit" and slot.style.name != "identity":
        raise SettingsError(f"bad value {slot.style.name!r} for 'style': with stylize=first_object_hit the "
                            f"styles come from 'styled' BSDFs, so the integrator's own style must be identity")
    if len(slot.inner) not in (1, depth):
        expected = "1 count (one stylized level)" if depth == 1 else f"1 or {depth} counts (one per stylized level)"
        raise SettingsError(f"bad value {values.get('inner_samples')!r} for 'inner_samples': expected {expected}")
    max_depth = integer("max_depth", get_("max_depth"), -1)
    if max_depth == 0:
        raise SettingsError(f"bad value 0 for 'max_depth': expected -1 (unbounded) or an integer in [1, {COUNT_MAX}]")
    rr_depth = integer("rr_depth", get_("rr_depth"), 1)
    lights = str(get_("emitter_sampling"))
    if lights not in EMITTER_MODES:
        raise SettingsError(f"bad value {lights!r} for 'emitter_sampling': expected one of {', '.join(EMITTER_MODES)}")
    hide = boolean("hide_emitters", get_("hide_emitters"))
    reuse, radius, k, mis = parse_reuse(values, slot, stylize)
    return Settings(slot=slot, stylize=stylize, stylize_depth=depth, max_depth=max_depth, rr_depth=rr_depth,
                    emitter_sampling=lights, hide_emitters=hide, reuse=reuse, reuse_radius=radius, reuse_k=k,
                    reuse_mis=mis)


def parse_reuse(values: Mapping[str, Any], slot: StyleSlot, stylize: str) -> tuple[str, int, int, str]:
    """`reuse`, `reuse_radius`, `reuse_k`, `reuse_mis`; reuse=pixels only where it is implemented."""
    mode = str(values.get("reuse", DEFAULTS["reuse"])).strip().lower()
    if mode not in REUSE_MODES:
        raise SettingsError(f"bad value {values.get('reuse')!r} for 'reuse': expected one of {', '.join(REUSE_MODES)}")
    radius = integer("reuse_radius", values.get("reuse_radius", DEFAULTS["reuse_radius"]), 1, MAX_REUSE_RADIUS)
    k = integer("reuse_k", values.get("reuse_k", DEFAULTS["reuse_k"]), 1, min((2 * radius + 1) ** 2 - 1, MAX_REUSE_K))
    mis = str(values.get("reuse_mis", DEFAULTS["reuse_mis"])).strip().lower()
    if mis not in REUSE_WEIGHTS:
        raise SettingsError(f"bad value {values.get('reuse_mis')!r} for 'reuse_mis': expected one of "
                            f"{', '.join(REUSE_WEIGHTS)}")
    if mode != "off":
        if stylize != "first_hit":
            raise SettingsError(f"bad value {stylize!r} for 'stylize': reuse={mode} pools samples at the first hit "
                                f"only; use stylize=first_hit or reuse=off")
        check_reusable(slot)
    return mode, radius, k, mis


def check_reusable(slot: StyleSlot, where: str = "the integrator's style") -> None:
    """reuse=pixels estimates g(mean of the pooled samples): direct application, a style of expectation."""
    if slot.style.per_sample:
        raise SettingsError(f"style '{slot.style.name}' ({where}) cannot be used with reuse=pixels: it applies g to "
                            f"every child sample, reuse pools samples before g")
    if slot.estimator != "direct":
        raise SettingsError(f"bad value {slot.estimator!r} for 'estimator' ({where}): reuse=pixels supports "
                            f"'direct' only (g of the pooled mean)")


def refine(base: Mapping[str, Any], changes: Mapping[str, Any]) -> dict[str, Any]:
    """`base` property values (a scene's own integrator) with `changes` applied; a new style drops the old
    style's parameters, which belong to it."""
    values = dict(base)
    new_style = changes.get("style")
    if new_style is not None and new_style != values.get("style", DEFAULTS["style"]):
        old = {p.name for p in get(str(values.get("style", DEFAULTS["style"]))).params}
        values = {k: v for k, v in values.items() if k not in old}
    values.update(changes)
    return values


def properties_of(props) -> dict[str, Any]:
    """mi.Properties -> plain dict (reading marks each entry as used; `parse` validates them)."""
    return {key: props[key] for key in props.keys()}


__all__ = ["Property", "PROPERTIES", "DEFAULTS", "STYLIZE_MODES", "REUSE_MODES", "check_reusable", "StyleSlot", "Settings", "parse", "parse_slot",
           "parse_inner", "integer", "boolean", "refine", "properties_of"]
