"""The `stylized` integrator's settings: names, defaults, parsing, docs, refinement, in one place.

Every front end goes through here: Mitsuba properties (XML, dicts), the command line's flags and
`--set`, and the Python API's keywords. A mapping of property values is parsed once into `Settings`;
bad values raise `SettingsError` (or `StyleError` for the style's own parameters) with one line.
The property table in docs/python.md is generated from `PROPERTIES`, which declares each property
once (`declare.Property`: type, default, bounds, choices, doc line and flag).

    settings = parse({"style": "cel", "inner_samples": "8,4", "stylize": "first_n_hits",
                      "stylize_depth": 2})
    values = refine_values(scene_integrator.values, {"inner_samples": 16})  # a scene's, refined
"""
from __future__ import annotations

from dataclasses import dataclass, field, fields, replace
from typing import Any, Mapping

from styletrace.config import estimator_registry
from styletrace.config import light_groups as LG
from styletrace.config.choices import DEFAULT_TESTS as LINE_TESTS_DEFAULT
from styletrace.config.choices import EMITTER_DEFAULT, EMITTER_MODES, LineSettings
from styletrace.config.choices import MODES as LINE_MODES
from styletrace.config.choices import TESTS as LINE_TESTS
from styletrace.config.declare import (
    COUNT_MAX,
    Property,
    boolean,
    integer,
    number,
    parse_names,
    rgb,
)
from styletrace.config.line_types import parse_line_types
from styletrace.errors import SettingsError
from styletrace.styles import create, style_class
from styletrace.styles.base import Style

STYLIZE_MODES = {
    "first_hit": "the camera ray's first hit; objects with a `styled` BSDF use their own style",
    "first_n_hits": "the first N vertices of every path, recursively",
    "first_object_hit": "the first vertex on a styled object at any depth (through mirrors and "
                        "glass)",
}

REUSE_MODES = {
    "off": "every camera sample uses its own children (the tree sampler)",
    "pixels": "pool the children of neighbouring pixels' first hits (first_hit, first_n_hits; "
              "docs/reuse.md)",
}
REUSE_WEIGHTS = ("balance", "pairwise")
REUSE_DEEP = {
    "tree": "each child's second-level value from the tree sampler (its own children)",
    "world": "second-level vertices pool their world-space neighbours' children too (within "
             "reuse_h)",
}
#: Smallest world-space radius reuse_h (a fraction of the scene's bounding-box diagonal): the world
#: grid packs 21 bits per axis of a cell index into one key (world_grid.py).
MIN_REUSE_H = 1e-4
#: Most children per pixel of the expansion pass (its children are traced in one loop per pixel).
MAX_EXPANSION_PASS = 4096
#: Estimators that take their first level's expansion point from the expansion pass.
EXPANSION_ESTIMATORS = ("series",)
#: Largest pixel window half-size for reuse=pixels (a 17 x 17 window).
MAX_REUSE_RADIUS = 8
#: Most neighbours a pool holds: the kernel keeps a pool as one bit per neighbour (and one for the
#: vertex itself) in a UInt64, and the cost grows as (K+1)^2 (every pooled sample's mixture density
#: sums K+1 terms).
MAX_REUSE_K = 63

PROPERTIES = (
    Property(
        "style",
        "identity",
        "string",
        "registry name of the style (`styletrace styles`)",
        "--style",
        "NAME",
    ),
    Property(
        "inner_samples",
        None,
        "int or list",
        "n: child estimates per stylized vertex; `8,4` sets one per level; `4:64` is adaptive: 4 "
        "children, up to 64 where the predicted error is large (direct only; docs/adaptive.md; "
        "with reuse=pixels, a refinement round of the pooled mean, docs/reuse.md)",
        "--inner",
        "N",
    ),
    Property(
        "adaptive_z",
        2.0,
        "float",
        "adaptive `n0:n_max`: keep drawing while a threshold of a step style lies within a "
        "confidence band of the children's mean brightness: adaptive_z normal deviations' "
        "confidence, Student's t standard errors",
        "",
        "",
        low=0.0,
        high=1e6,
        low_open=True,
    ),
    Property(
        "adaptive_bias",
        2e-3,
        "float",
        "adaptive `n0:n_max`: keep drawing while a smooth style's predicted "
        "direct-application bias, the magnitude of g'' Var / (2n) (Eq. 21), exceeds this",
        "",
        "",
        low=0.0,
        high=1e6,
        low_open=True,
    ),
    Property(
        "aovs",
        False,
        "bool",
        "also output per-pixel error channels: the variance of the pixel's estimate, the predicted "
        "bias (Eq. 21) and the children used at the first stylized vertex (direct only; `--aovs`)",
        "",
        "",
    ),
    Property(
        "estimator",
        "direct",
        "string",
        "how g(E[L]) is estimated from the children: "
        + ", ".join(estimator_registry.estimator_names()),
        "--estimator",
        "NAME",
    ),
    Property(
        "expansion_pass",
        0,
        "int",
        "estimator series: m > 0 runs a pre-pass of m children per pixel at the first stylized "
        "vertex; the first level's series then expands about 2x the larger b* = E[x^2]/E[x] of the "
        "pixel's and its 3x3 window's children (independent of the estimate's; m at most "
        f"{MAX_EXPANSION_PASS}), geometric truncation; 0: b from each estimate's own pilot "
        "(docs/estimators.md)",
        "--expansion-pass",
        "M",
        low=0,
        high=MAX_EXPANSION_PASS,
    ),
    Property(
        "firefly",
        None,
        "float",
        "firefly control of direct application: the brightest of a stylized vertex's n children is "
        "capped at k times the larger of the others' mean brightness and firefly_floor (a lone "
        "child: 10 / 0.18 times firefly_floor); 0: off, the paper's estimator; auto: 4 where the "
        "render is denoised, else 0 (docs/look.md)",
        "--firefly",
        "K",
        low=0.0,
    ),
    Property(
        "firefly_floor",
        None,
        "float",
        "firefly control: the brightness below which a child is never an "
        "outlier; auto: the scene's median first-hit brightness (the pilot)",
        low=0.0,
    ),
    Property(
        "light_groups",
        "",
        "string",
        "light groups and their styles, `name:style;name:style` (`key:cel;fill:identity`); an "
        "emitter joins one by `__lg_<name>` in its id, `<name>.<param>` sets a group's style "
        "parameters, estimator, inner_samples (docs/light_groups.md)",
        "--light-groups",
        "SPEC",
    ),
    Property(
        "stylize",
        "first_hit",
        "string",
        "where styles apply: " + ", ".join(STYLIZE_MODES),
        "--stylize",
        "MODE",
        choices=tuple(STYLIZE_MODES),
    ),
    Property(
        "stylize_depth",
        1,
        "int",
        "N, the number of stylized levels (at most 16; the trace time grows linearly with it)",
        "--stylize-depth",
        "N",
    ),
    Property(
        "max_depth",
        -1,
        "int",
        "longest path, as Mitsuba's `path` (-1: unbounded)",
        "--max-depth",
        "D",
    ),
    Property(
        "emitter_sampling",
        EMITTER_DEFAULT,
        "string",
        "how next-event estimation picks a light: auto (spatial where the scene's sampler is "
        "owen_sobol and it has several lights, else uniform), uniform (as Mitsuba), power (by "
        "estimated emitted power: better with lights of very different strengths, worse where a "
        "sky dominates the estimate) or spatial (per shading point, by power, distance and "
        "orientation: for rooms with many lights; docs/design/spatial_emitter_selection.md); "
        "BENCHMARKS.md",
        "--emitter-sampling",
        "MODE",
        choices=tuple(EMITTER_MODES),
    ),
    Property(
        "rr_depth",
        5,
        "int",
        "depth at which Russian roulette starts, as Mitsuba's `path`",
        "--rr-depth",
        "D",
        low=1,
    ),
    Property(
        "hide_emitters",
        False,
        "bool",
        "camera rays do not see emitters, as Mitsuba's `path`: they pass "
        "through area lights and find black (alpha 0) where they escape",
        "--hide-emitters",
        "BOOL",
    ),
    # feature lines (kernel/lines.py, docs/lines.md)
    Property(
        "lines",
        False,
        "bool",
        "physically based feature lines on path edges (docs/lines.md)",
        "--lines",
        "BOOL",
        bare=True,
    ),
    Property(
        "line_width",
        2.0,
        "float",
        "a line's width in pixels at the camera (kept in mirrors)",
        low=0.0,
        high=64.0,
        low_open=True,
    ),
    Property(
        "line_samples",
        8,
        "int",
        "N, auxiliary rays per tested edge (coverage 1 - (1 - q)^N)",
        low=1,
        high=256,
    ),
    Property(
        "line_depth",
        1,
        "int",
        "edges tested: 0 .. line_depth - 1 (1: the camera ray only; 2: also what a "
        "mirror or glass at the first hit shows)",
        low=1,
        high=64,
    ),
    Property(
        "line_tests",
        ",".join(LINE_TESTS_DEFAULT),
        "list",
        "which tests draw lines: " + ", ".join(LINE_TESTS),
    ),
    Property(
        "line_crease",
        0.3,
        "float",
        "crease test: 1 - abs(n . n') above this draws a line",
        low=0.0,
        high=1.0,
    ),
    Property(
        "line_albedo",
        0.1,
        "float",
        "albedo test: a luminance difference above this draws a line",
        low=0.0,
    ),
    Property(
        "line_slope",
        2.0,
        "float",
        "depth test: a point's distance from the other's tangent plane above this "
        "times the stencil radius draws a line",
        low=0.0,
    ),
    Property("line_color", "0,0,0", "rgb", "the lines' colour"),
    Property(
        "line_gradient",
        "",
        "string",
        "instead of line_color, a gradient over world y: `r,g,b;r,g,b` (over "
        "the scene's bounding box) or `r,g,b;r,g,b;y0;y1`",
    ),
    Property("line_objects", "", "list", "ids of the shapes that draw lines (empty: all)"),
    Property(
        "line_mode",
        "absorb",
        "string",
        "absorb (West 2021: N rays against the path's own ray; a line ends the path), expectation "
        "(LLaT: g = (1 - w) c + w L, w = E[m]^k from k random stencil pairs) or lifted (LLaT's "
        "conditional lifting: auxiliary paths per `line_types` entry; the first type that fires "
        "colours the camera sample, L is traced only where none does)",
        choices=tuple(LINE_MODES),
    ),
    Property(
        "line_k",
        12,
        "int",
        "expectation mode: k, the opacity control (more: lines darker and wider)",
        low=1,
        high=256,
    ),
    Property(
        "line_types",
        "",
        "string",
        "lifted mode: the line dictionary, in priority order: `measurement key=value ...; ...` "
        "(measurements shape_id, material_id, depth, normal; fields threshold, stencil, radius, "
        "count, color; docs/lines.md). Empty: one shape_id type",
    ),
    Property(
        "line_diffuse",
        False,
        "bool",
        "lifted mode: auxiliary paths go on through diffuse vertices by the minimal rotation of "
        "the base path's direction (off: they stop there, as in the other modes)",
    ),
    Property(
        "reuse",
        "off",
        "string",
        "sample reuse at the stylized vertex: "
        + ", ".join(REUSE_MODES)
        + " (Tong and Hachisuka 2025; docs/reuse.md)",
        "--reuse",
        "MODE",
    ),
    Property(
        "reuse_radius",
        2,
        "int",
        f"reuse=pixels: half-size r of the pixel window the neighbours come from "
        f"((2r+1) x (2r+1), r at most {MAX_REUSE_RADIUS})",
        "--reuse-radius",
        "R",
    ),
    Property(
        "reuse_k",
        8,
        "int",
        "reuse=pixels: neighbours pooled per camera sample, drawn from the window "
        f"(at most (2r+1)^2 - 1 and {MAX_REUSE_K})",
        "--reuse-k",
        "K",
    ),
    Property(
        "reuse_mis",
        "balance",
        "string",
        "reuse=pixels: weights of the pooled BSDF samples: balance (the mixture density of the "
        "whole pool, (K+1)^2 density evaluations) or pairwise (each neighbour against the vertex "
        "itself, 2K+1; docs/reuse.md)",
        "--reuse-mis",
        "NAME",
    ),
    Property(
        "reuse_deep",
        "tree",
        "string",
        "reuse=pixels with first_n_hits at depth 2: the second level's values: tree (estimated per "
        "child) or world (pooled over world-space neighbours, Tong and Hachisuka 2025; "
        "docs/reuse.md)",
        "",
        "",
    ),
    Property(
        "reuse_h",
        0.0,
        "float",
        "reuse_deep=world: radius h of a second-level vertex's neighbours and the world grid's "
        "cell size, as a fraction of the scene's bounding-box diagonal (at least "
        f"{MIN_REUSE_H:g}); 0: from the vertices' density, a cell holding about reuse_k2 of them",
        "",
        "",
    ),
    Property(
        "reuse_k2",
        16,
        "int",
        f"reuse_deep=world: candidates a second-level vertex looks at in its cell (at "
        f"most {MAX_REUSE_K})",
        "",
        "",
        low=1,
        high=MAX_REUSE_K,
    ),
)
DEFAULTS = {p.name: p.default for p in PROPERTIES}


def declare(prop: Property) -> Property:
    """Add an integrator property: its flag, docs row, parsing and `Settings` attribute follow
    (declare.py); `parse` puts its value in `Settings.extra`, read as an attribute.

    Args:
        prop: the new property's declaration.

    Returns:
        `prop`.

    Raises:
        ValueError: a property of that name is declared already.
    """
    global PROPERTIES
    if prop.name in DEFAULTS:
        raise ValueError(f"integrator property {prop.name!r} is declared already")
    PROPERTIES = PROPERTIES + (prop,)
    DEFAULTS[prop.name] = prop.default
    return prop


def value(key: str, values: Mapping[str, Any]) -> Any:
    """The value of property `key` in `values` (else its default), parsed as its declaration
    says.

    Args:
        key: a declared property's name (`PROPERTIES`).
        values: property name -> raw value (CLI strings, Mitsuba properties or Python values).

    Returns:
        The parsed value; None where the value and the default are both None (auto).

    Raises:
        SettingsError: the value is not what the declaration allows.
    """
    prop = next(p for p in PROPERTIES if p.name == key)
    raw = values.get(key, prop.default)
    return None if raw is None and prop.default is None else prop.parse(raw)
#: the style `styletrace render` uses on a scene without a `stylized` integrator of its own
COMMAND_LINE_STYLE = "cel"
#: what a `styled` BSDF accepts besides its style's parameters
SLOT_KEYS = ("style", "inner_samples", "estimator")
#: properties Mitsuba's SamplingIntegrator reads itself
BASE_KEYS = ("samples_per_pass", "timeout")
#: Most stylized levels for first_n_hits/first_object_hit. Each level's loop is traced inside the
#: draw of the one above; with Dr.Jit's JitFlag.OptimizeLoops, which traces a symbolic loop's body
#: twice, the trace time doubled per level (52 s at 12 levels), so the cap was 8. styletrace traces
#: with the flag off (`integrator.tracing`) and the trace time grows linearly (BENCHMARKS.md,
#: recursion depth; tests/kernel/test_recursion_depth.py). 16 levels of one child each already make
#: a path of 16 stylized vertices; the cap keeps the kernel and Python's recursion (1000 levels
#: overflow it) bounded.
MAX_STYLIZE_DEPTH = 16


class AdaptiveCount(int):
    """An adaptive inner count `n0:n_max`: an int equal to n0 (what code that wants one count sees),
    with n_max.

    Args:
        n0: the children every estimate draws first.
        n_max: the most children an estimate may draw (>= n0; `parse_inner` checks it).
    """

    def __new__(cls, n0: int, n_max: int):
        out = super().__new__(cls, n0)
        out.n_max = n_max
        return out

    def __repr__(self) -> str:
        return f"{int(self)}:{self.n_max}"

    __str__ = __repr__

    def __eq__(self, other):
        return (isinstance(other, AdaptiveCount)
                and (int(self), self.n_max) == (int(other), other.n_max))

    def __hash__(self):
        return hash((int(self), self.n_max))


def adaptive(inner: tuple[int, ...]) -> bool:
    """Whether any level's inner count is adaptive.

    Args:
        inner: the inner counts, one per stylized level (`StyleSlot.inner`).

    Returns:
        True where one of them is an `AdaptiveCount`.
    """
    return any(isinstance(n, AdaptiveCount) for n in inner)


@dataclass(frozen=True)
class StyleSlot:
    """A style with its inner sample counts (one per stylized level, or one for all) and
    estimator."""

    style: Style
    inner: tuple[int, ...]
    estimator: str = "direct"

    def n(self, level: int) -> int:
        """The inner count at a stylized level.

        Args:
            level: the stylized level, 0 for the first; past the last count, the last applies.

        Returns:
            The count (an `AdaptiveCount` where it is adaptive).
        """
        return self.inner[min(level, len(self.inner) - 1)]


@dataclass(frozen=True)
class Settings:
    """The parsed properties (`parse` fills every field; the defaults live in the declarations,
    PROPERTIES)."""
    slot: StyleSlot                 # the integrator's own style (identity: physically based)
    stylize: str
    stylize_depth: int
    max_depth: int
    rr_depth: int
    emitter_sampling: str
    hide_emitters: bool
    lines: LineSettings | None  # None: no line code is traced
    adaptive_z: float
    adaptive_bias: float
    aovs: bool
    reuse: str
    reuse_radius: int
    reuse_k: int
    reuse_mis: str
    reuse_deep: str
    reuse_h: float
    reuse_k2: int
    expansion_pass: int
    #: declared properties that no field above holds (`declare`): parsed by their declaration,
    #: read as attributes
    extra: Mapping[str, Any] = field(default_factory=dict)
    #: the light groups (`config.light_groups`): () where none is declared, else `default` (the
    #: integrator's slot) first
    light_groups: tuple = ()

    def __getattr__(self, name: str) -> Any:
        extra = self.__dict__.get("extra", {})
        if name in extra:
            return extra[name]
        raise AttributeError(f"'Settings' object has no attribute {name!r}")

    @property
    def style(self) -> Style:
        return self.slot.style

    @property
    def inner(self) -> tuple[int, ...]:
        return self.slot.inner

    def describe(self) -> str:
        return (
            f"style={self.style.describe()}, inner={list(self.inner)}, "
            f"estimator={self.slot.estimator}, stylize={self.stylize}, "
            f"stylize_depth={self.stylize_depth}, max_depth={self.max_depth}"
            + ("" if self.lines is None else f", {self.lines.describe()}")
            + (
                f", reuse={self.reuse}(r={self.reuse_radius}, k={self.reuse_k}, {self.reuse_mis})"
                if self.reuse != "off"
                else ""
            )
            + (
                f", reuse_deep=world(h={self.reuse_h or 'auto'}, k2={self.reuse_k2})"
                if self.reuse_deep == "world"
                else ""
            )
            + (f", expansion_pass={self.expansion_pass}" if self.expansion_pass else "")
        )



#: properties parsed into a field of their own or into a group (the style slot, the lines) at import
#: time; a property declared later (`declare`) is parsed by its declaration alone into
#: `Settings.extra`
GROUPED = frozenset(
    {f.name for f in fields(Settings)}
    | set(SLOT_KEYS)
    | set(BASE_KEYS)
    | {p.name for p in PROPERTIES if p.name == "lines" or p.name.startswith("line_")}
)

def parse_lines(values: Mapping[str, Any]) -> LineSettings | None:
    """The `line_*` properties: None where `lines` is off (then the others are still checked).

    Args:
        values: property name -> raw value; missing names take DEFAULTS.

    Returns:
        The parsed line group, or None where `lines` is off.

    Raises:
        SettingsError: a bad value, no test with lines on, line_gradient with line_mode lifted,
            or line_types without it.
    """
    get_ = lambda key: values.get(key, DEFAULTS[key])  # noqa: E731
    on = boolean("lines", get_("lines"))
    tests = parse_names("line_tests", get_("line_tests"))
    for t in tests:
        if t not in LINE_TESTS:
            raise SettingsError(f"bad value {t!r} in 'line_tests': expected some of "
                                f"{', '.join(LINE_TESTS)}")
    gradient = None
    raw = get_("line_gradient")
    if raw not in ("", None):
        parts = raw.split(";") if isinstance(raw, str) else list(raw)
        if len(parts) not in (2, 4):
            raise SettingsError(f"bad value {raw!r} for 'line_gradient': expected r,g,b;r,g,b or "
                                "r,g,b;r,g,b;y0;y1")
        ys = [number("line_gradient", y, -float("inf")) for y in parts[2:]] or [None, None]
        gradient = (rgb("line_gradient", parts[0]), rgb("line_gradient", parts[1]), ys[0], ys[1])
    lines = LineSettings(
        width=value("line_width", values),
        samples=value("line_samples", values),
        depth=value("line_depth", values),
        tests=tests,
        crease=value("line_crease", values),
        albedo=value("line_albedo", values),
        slope=value("line_slope", values),
        color=value("line_color", values),
        gradient=gradient,
        objects=value("line_objects", values),
        mode=value("line_mode", values),
        k=value("line_k", values),
    )
    if on and not tests:
        raise SettingsError(
            f"bad value {get_('line_tests')!r} for 'line_tests': lines need at least one of "
            f"{', '.join(LINE_TESTS)}"
        )
    raw_types = get_("line_types")
    if lines.mode == "lifted":
        if get_("line_gradient") not in ("", None, ()):
            raise SettingsError(
                "'line_gradient' is not drawn by line_mode lifted: its lines take each line type's "
                "colour (use line_mode absorb or expectation)"
            )
        lines = replace(
            lines,
            types=parse_line_types(raw_types, lines.width, lines.samples, lines.color),
            diffuse=value("line_diffuse", values),
        )
    elif raw_types not in ("", None):
        raise SettingsError(
            f"bad value {raw_types!r} for 'line_types': line types are read by line_mode lifted "
            f"only (line_mode is {lines.mode!r})"
        )
    return lines if on else None


def parse_inner(raw: Any, default: int) -> tuple[int, ...]:
    """`inner_samples`: one count, or one per stylized level ('8,4', [8, 4] or (8, 4)); a count
    `n0:n_max` (a string) is adaptive (`AdaptiveCount`), e.g. '4:64' or '4:64,2:8'.

    Args:
        raw: the property's value: None, a count, a string (',' or ';' between levels) or a list.
        default: the count where `raw` is None (the style's own).

    Returns:
        The counts, each >= 1.

    Raises:
        SettingsError: no count, a count not an integer >= 1, or an adaptive n_max < n0.
    """
    if raw is None:
        return (default,)
    if isinstance(raw, str):
        parts = [p for p in raw.replace(";", ",").split(",") if p.strip()]
    elif isinstance(raw, (list, tuple)):
        parts = list(raw)
    else:
        parts = [raw]
    if not parts:
        raise SettingsError(f"bad value {raw!r} for 'inner_samples': expected an integer in [1, "
                            f"{COUNT_MAX}]")
    return tuple(_count(p) for p in parts)


def _count(part: Any) -> int:
    if isinstance(part, AdaptiveCount):
        return part
    if isinstance(part, str) and ":" in part:
        lo, _, hi = part.partition(":")
        n0, n_max = integer("inner_samples", lo, 1), integer("inner_samples", hi, 1)
        if n_max < n0:
            raise SettingsError(
                f"bad value {part.strip()!r} for 'inner_samples': an adaptive count n0:n_max "
                f"needs n0 <= n_max"
            )
        return AdaptiveCount(n0, n_max)
    return integer("inner_samples", part, 1)


def parse_slot(values: Mapping[str, Any], context: str = "the stylized integrator",
               extra_keys: tuple[str, ...] = ()) -> StyleSlot:
    """A style, its parameters, inner_samples and estimator from a flat mapping.

    Args:
        values: property name -> raw value (style, its parameters, inner_samples, estimator).
        context: who reads them, for the errors; extra_keys: names allowed besides the slot's.

    Returns:
        The slot, its estimator checked against the style.

    Raises:
        SettingsError: an unknown key, a bad estimator or inner count.
        StyleError: an unknown style, or a bad value of its parameters.
    """
    values = dict(values)
    style_name = str(values.pop("style", DEFAULTS["style"]))
    cls = style_class(style_name)
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
    slot = StyleSlot(style=style, inner=inner,
                     estimator=estimator_registry.check_estimator(name, style))
    if adaptive(inner):
        estimator_registry.check_adaptive(name, style, values.get("inner_samples"))
    return slot


def parse(values: Mapping[str, Any]) -> Settings:
    """Validated integrator settings from a flat name -> value mapping (property values, CLI strings
    or Python values); missing names take DEFAULTS.

    Args:
        values: property name -> raw value; `samples_per_pass` is refused (styletrace sets passes).

    Returns:
        The settings, every field filled.

    Raises:
        SettingsError: a bad value, or values that do not go together.
        StyleError: an unknown style, or a bad value of its parameters.
    """
    if "samples_per_pass" in values:
        raise SettingsError(
            f"bad value {values['samples_per_pass']!r} for 'samples_per_pass': the stylized "
            f"integrator renders in styletrace's own passes; set the camera samples per pass with "
            f"`--pass-spp` (command line) or passes(lanes_per_pass=...) (Python) instead"
        )
    own = tuple(p.name for p in PROPERTIES if p.name not in SLOT_KEYS)
    grouped = LG.group_keys(values)  # `<group>.<key>`: a light group's, parsed below
    slot = parse_slot({k: v for k, v in values.items() if k not in grouped},
                      extra_keys=own + BASE_KEYS)
    get_ = lambda key: values.get(key, DEFAULTS[key])  # noqa: E731
    stylize = value("stylize", values)
    depth = integer("stylize_depth", get_("stylize_depth"), 1, MAX_STYLIZE_DEPTH)
    if stylize == "first_hit" and depth != 1:
        raise SettingsError(
            f"bad value {depth!r} for 'stylize_depth': 'first_hit' stylizes one level; "
            f"use stylize=first_n_hits or first_object_hit for more"
        )
    if stylize == "first_object_hit" and slot.style.name != "identity":
        raise SettingsError(
            f"bad value {slot.style.name!r} for 'style': with stylize=first_object_hit the "
            f"styles come from 'styled' BSDFs, so the integrator's own style must be identity"
        )
    if len(slot.inner) not in (1, depth):
        expected = ("1 count (one stylized level)" if depth == 1
                    else f"1 or {depth} counts (one per stylized level)")
        raise SettingsError(f"bad value {values.get('inner_samples')!r} for 'inner_samples': "
                            f"expected {expected}")
    max_depth = integer("max_depth", get_("max_depth"), -1)
    if max_depth == 0:
        raise SettingsError("bad value 0 for 'max_depth': expected -1 (unbounded) or an integer in "
                            f"[1, {COUNT_MAX}]")
    rr_depth, lights = value("rr_depth", values), value("emitter_sampling", values)
    hide = value("hide_emitters", values)
    z, target, aovs = (value("adaptive_z", values), value("adaptive_bias", values),
                       value("aovs", values))
    if aovs and slot.estimator != "direct":
        raise SettingsError(
            f"bad value True for 'aovs' with estimator '{slot.estimator}': the error AOVs "
            "(variance, Eq. 21 bias, children) are those of direct application; use "
            "estimator=direct"
        )
    reuse, radius, k, mis = parse_reuse(values, slot, stylize)
    deep, h, k2 = parse_reuse_deep(values, slot, reuse, stylize, depth)
    lines = parse_lines(values)
    if reuse != "off" and (lines is not None or aovs):
        what = "'lines'" if lines is not None else "'aovs'"
        raise SettingsError(
            f"bad value True for {what} with reuse={reuse}: a pooled pass traces its own camera "
            f"rays and keeps no per-sample statistics; use reuse=off"
        )
    expansion = parse_expansion(values, slot)
    firefly = value("firefly", values)
    if firefly is not None and 0.0 < firefly < 1.0:
        raise SettingsError(f"bad value {firefly!r} for 'firefly': expected 0 (off) or a number >= "
                            "1")
    settings = Settings(
        slot=slot,
        stylize=stylize,
        stylize_depth=depth,
        max_depth=max_depth,
        rr_depth=rr_depth,
        emitter_sampling=lights,
        hide_emitters=hide,
        lines=lines,
        adaptive_z=z,
        adaptive_bias=target,
        aovs=aovs,
        reuse=reuse,
        reuse_radius=radius,
        reuse_k=k,
        reuse_mis=mis,
        reuse_deep=deep,
        reuse_h=h,
        reuse_k2=k2,
        expansion_pass=expansion,
        extra={p.name: value(p.name, values) for p in PROPERTIES if p.name not in GROUPED},
        light_groups=LG.parse_groups(values, parse_slot, slot),
    )
    LG.check_supported(settings.light_groups, settings)
    return settings


def parse_expansion(values: Mapping[str, Any], slot: StyleSlot) -> int:
    """`expansion_pass`: 0 (off) or the children per pixel of the pre-pass, for the series estimator
    only.

    Args:
        values: property name -> raw value.
        slot: the parsed style slot, whose estimator the pass must serve.

    Returns:
        m, in [0, MAX_EXPANSION_PASS].

    Raises:
        SettingsError: a bad value, or m > 0 with an estimator other than EXPANSION_ESTIMATORS.
    """
    m = value("expansion_pass", values)
    if m and slot.estimator not in EXPANSION_ESTIMATORS:
        raise SettingsError(
            f"bad value {m} for 'expansion_pass' with estimator '{slot.estimator}': the pass gives "
            f"the expansion point of estimator {', '.join(EXPANSION_ESTIMATORS)} only; use 0"
        )
    # reuse=pixels takes estimator direct only (check_reusable), so it never meets the pass
    return m


def parse_reuse(values: Mapping[str, Any], slot: StyleSlot,
                stylize: str) -> tuple[str, int, int, str]:
    """`reuse`, `reuse_radius`, `reuse_k`, `reuse_mis`; reuse=pixels only where it is
    implemented.

    Args:
        values: property name -> raw value (names and weights in any case, spaces stripped).
        slot: the parsed style slot (`check_reusable`); stylize: the parsed `stylize` mode.

    Returns:
        (mode, radius r, neighbours k <= min((2r+1)^2 - 1, MAX_REUSE_K), weights).

    Raises:
        SettingsError: a bad value, or reuse=pixels where it is not implemented.
    """
    mode = str(values.get("reuse", DEFAULTS["reuse"])).strip().lower()
    if mode not in REUSE_MODES:
        raise SettingsError(f"bad value {values.get('reuse')!r} for 'reuse': expected one of "
                            f"{', '.join(REUSE_MODES)}")
    radius = integer("reuse_radius", values.get("reuse_radius", DEFAULTS["reuse_radius"]), 1,
                     MAX_REUSE_RADIUS)
    k = integer("reuse_k", values.get("reuse_k", DEFAULTS["reuse_k"]), 1,
                min((2 * radius + 1) ** 2 - 1, MAX_REUSE_K))
    mis = str(values.get("reuse_mis", DEFAULTS["reuse_mis"])).strip().lower()
    if mis not in REUSE_WEIGHTS:
        raise SettingsError(
            f"bad value {values.get('reuse_mis')!r} for 'reuse_mis': expected one of "
            f"{', '.join(REUSE_WEIGHTS)}"
        )
    if mode != "off":
        if stylize not in ("first_hit", "first_n_hits"):
            raise SettingsError(
                f"bad value {stylize!r} for 'stylize': reuse={mode} pools samples at the first hit "
                f"(first_hit, first_n_hits) only; use one of those or reuse=off"
            )
        check_reusable(slot)
    return mode, radius, k, mis


def parse_reuse_deep(values: Mapping[str, Any], slot: StyleSlot, reuse: str, stylize: str,
                     depth: int) -> tuple[str, float, int]:
    """`reuse_deep`, `reuse_h`, `reuse_k2`; world-space pooling only at first_n_hits depth 2.

    Args:
        values: property name -> raw value.
        slot: the parsed style slot (`check_reusable` where reuse_deep is world).
        reuse, stylize, depth: the parsed `reuse`, `stylize` and `stylize_depth`.

    Returns:
        (reuse_deep, reuse_h in {0} or [MIN_REUSE_H, 1], reuse_k2).

    Raises:
        SettingsError: a bad value, or world pooling without reuse=pixels at first_n_hits depth 2.
    """
    deep = str(values.get("reuse_deep", DEFAULTS["reuse_deep"])).strip().lower()
    if deep not in REUSE_DEEP:
        raise SettingsError(
            f"bad value {values.get('reuse_deep')!r} for 'reuse_deep': expected one of "
            f"{', '.join(REUSE_DEEP)}"
        )
    h = number("reuse_h", values.get("reuse_h", DEFAULTS["reuse_h"]), 0.0, 1.0)
    if 0.0 < h < MIN_REUSE_H:
        raise SettingsError(
            f"bad value {values.get('reuse_h')!r} for 'reuse_h': expected 0 (from the vertices' "
            f"density) or a number in [{MIN_REUSE_H:g}, 1]"
        )
    k2 = value("reuse_k2", values)
    if deep == "world" and (reuse == "off" or stylize != "first_n_hits" or depth != 2):
        raise SettingsError(
            f"bad value 'world' for 'reuse_deep': world-space pooling needs reuse=pixels with "
            f"stylize=first_n_hits and stylize_depth 2 (here reuse={reuse}, stylize={stylize}, "
            f"stylize_depth {depth})"
        )
    if deep == "world":
        check_reusable(slot, deep=deep)
    return deep, h, k2


def check_reusable(slot: StyleSlot, where: str = "the integrator's style",
                   deep: str = "tree") -> None:
    """reuse=pixels estimates g(mean of the pooled samples): direct application, a style of
    expectation (an adaptive count n0:n_max adds a refinement round at the first hit, docs/reuse.md;
    not with reuse_deep=world, whose first-level children are drawn all at once).

    Args:
        slot: the style slot to pool for.
        where: whose slot it is, as the errors say it.
        deep: the parsed `reuse_deep`; "world" also refuses adaptive counts at levels 0 and 1.

    Raises:
        SettingsError: a per-sample style, an estimator other than direct, or (world) an adaptive
            count.
    """
    if deep == "world":
        for level in (0, 1):
            n = slot.n(level)
            if isinstance(n, AdaptiveCount):
                raise SettingsError(f"bad value '{n!r}' for 'inner_samples' ({where}) with "
                                    "reuse_deep=world: fixed counts only there; use "
                                    "reuse_deep=tree for adaptive counts")
    if slot.style.per_sample:
        raise SettingsError(
            f"style '{slot.style.name}' ({where}) cannot be used with reuse=pixels: it applies g "
            "to every child sample, reuse pools samples before g"
        )
    if slot.estimator != "direct":
        raise SettingsError(
            f"bad value {slot.estimator!r} for 'estimator' ({where}): reuse=pixels supports "
            f"'direct' only (g of the pooled mean)"
        )


def refine_values(base: Mapping[str, Any], changes: Mapping[str, Any]) -> dict[str, Any]:
    """`base` property values (a scene's own integrator) with `changes` applied; a new style drops
    the old style's parameters, which belong to it.

    Args:
        base: property name -> raw value, as the scene's integrator has them (not changed).
        changes: property name -> raw value to set; a `style` other than base's drops its params.

    Returns:
        A new mapping, not yet parsed.

    Raises:
        StyleError: base names an unknown style (read only where `changes` sets another style).
    """
    values = dict(base)
    new_style = changes.get("style")
    if new_style is not None and new_style != values.get("style", DEFAULTS["style"]):
        old = {p.name for p in style_class(str(values.get("style", DEFAULTS["style"]))).params}
        values = {k: v for k, v in values.items() if k not in old}
    values.update(changes)
    return values


def properties_of(props) -> dict[str, Any]:
    """mi.Properties -> plain dict (reading marks each entry as used; `parse` validates them).

    Args:
        props: a Mitsuba `mi.Properties` (the integrator's or a BSDF's).

    Returns:
        property name -> value, as Mitsuba holds it.
    """
    return {key: props[key] for key in props.keys()}


__all__ = [
    "Property",
    "PROPERTIES",
    "DEFAULTS",
    "MAX_EXPANSION_PASS",
    "EXPANSION_ESTIMATORS",
    "parse_expansion",
    "STYLIZE_MODES",
    "REUSE_MODES",
    "check_reusable",
    "StyleSlot",
    "Settings",
    "parse",
    "parse_slot",
    "parse_inner",
    "parse_lines",
    "AdaptiveCount",
    "adaptive",
    "integer",
    "number",
    "boolean",
    "refine_values",
    "properties_of",
]
