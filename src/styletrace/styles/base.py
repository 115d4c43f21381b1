"""The style interface: a style function g_theta applied to an estimate of expected radiance.

A style declares
- `name`, `summary`: registry key and one line for `styletrace styles`;
- `params`: its parameters theta (`Param`), validated on construction;
- `default_inner`: the inner sample count n it wants per evaluation (0 for closed-form styles);
- `apply(I, v)`: g_theta(I) for a radiance estimate I (mi.Color3f) at vertex `v` (`Vertex`),
  branch-free on Dr.Jit arrays (dr.select, no `if` on array values);
- optionally `form()`: g as an affine map, a power series or a polynomial fit (`forms.py`);
- for adaptive inner counts: `step_thresholds(v)`, the brightnesses where g jumps, and
  `curvature(I, v, h)`, g'' along the grey direction (docs/design/adaptive_stopping.md).
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Any, ClassVar, Mapping

from styletrace.gate import dr, mi
from styletrace.styles.params import Param, StyleError


def brightness(I: mi.Color3f) -> mi.Float:
    """u = (r + g + b) / 3, the brightness used by every setup of the paper's supplement (S5).

    Args:
        I: radiance per lane (mi.Color3f).

    Returns:
        u per lane (mi.Float).
    """
    return (I.x + I.y + I.z) * (1.0 / 3.0)


@dataclass
class Vertex:
    """Where a style is evaluated: all fields are Dr.Jit arrays over the lanes being stylized.

    p: world position; n: shading normal (world); wo: unit direction towards the viewer or previous
    vertex; view: the camera's forward direction (the same for all lanes); depth: 0 for the first
    hit seen from the camera. s: the vertex's image coordinate (mi.Point2f, pixels right and up of
    the image centre) where the integrator computes one (LLaT's canonical lifting,
    kernel/anchors.py: only while a style of the render has `wants_coordinate`), else None; method:
    how s was found (kernel/mls.py codes).
    """

    p: mi.Point3f
    n: mi.Vector3f
    wo: mi.Vector3f
    view: mi.Vector3f
    depth: mi.UInt32
    s: Any = None
    method: Any = None


#: parameter kinds `Style.opaque` makes kernel inputs; the others (int, bool, choice, vector,
#: gradient) shape the traced code or are read on the host, and stay literals
OPAQUE_KINDS = ("float", "floats", "color")


class Style:
    """A style g_theta (the module doc); subclasses declare name, summary, params, default_inner
    and `apply`.

    Args:
        **values: parameter name -> value (strings, numbers, sequences, as `Param.parse` reads
            them; None or 'auto': the auto rule); omitted parameters take their defaults.

    Raises:
        StyleError: an unknown parameter, a bad value, or values that do not go together.
    """

    name: ClassVar[str] = ""
    summary: ClassVar[str] = ""
    params: ClassVar[tuple[Param, ...]] = ()
    default_inner: ClassVar[int] = 8
    #: True for baselines that apply g to every child sample and average (not a function of
    #: expectation).
    per_sample: ClassVar[bool] = False

    def __init__(self, **values: Any):
        known = {p.name: p for p in self.params}
        for key in values:
            if key not in known:
                allowed = ", ".join(known) if known else "none"
                raise StyleError(f"unknown parameter '{key}' for style '{self.name}': allowed are "
                                 f"{allowed}")
        self.values: dict[str, Any] = {}
        #: the parameters given explicitly (not None/'auto'): `pinned` keeps them when it fills in
        #: auto values
        self.given: dict[str, Any] = {k: v for k, v in values.items() if v is not None}
        #: the parameters `pinned` filled in from the scene (auto values), as opposed to given ones
        self.chosen: tuple[str, ...] = ()
        for p in self.params:
            self.values[p.name] = p.parse(values[p.name]) if key_in(values, p.name) else p.default
        self.validate()

    def __getattr__(self, key: str) -> Any:
        values = self.__dict__.get("values")
        if values is not None and key in values:
            return values[key]
        raise AttributeError(key)

    @property
    def closed_form(self) -> bool:
        return self.default_inner == 0

    def validate(self) -> None:
        """Checks that involve several parameters at once; raise StyleError."""

    def prepare(self, scene: mi.Scene) -> None:
        """Called once per render before the kernel is traced (e.g. to read the camera).

        Args:
            scene: the scene about to be rendered.
        """

    def auto_values(self, facts) -> dict[str, Any]:
        """Values for the parameters left at 'auto' whose rule needs the scene (`scene.defaults`
        computes them before rendering; default: none).

        Args:
            facts: a `scene.defaults.Facts`: `camera` (a `Camera`), `brightness(qs)` and
                `depth(qs)`, quantiles of the first-hit brightness and camera depth of what this
                style covers.

        Returns:
            parameter name -> value, for `pinned`.
        """
        return {}

    def pinned(self, values: Mapping[str, Any]) -> "Style":
        """A new style of the same kind: the given parameters kept, `values` filling in auto ones
        (named in the new style's `chosen`).

        Args:
            values: parameter name -> value (e.g. `auto_values`' result).

        Returns:
            The new style.

        Raises:
            StyleError: a bad value.
        """
        out = type(self)(**{**self.given, **values})
        out.chosen = tuple(sorted(set(self.chosen) | set(values)))
        return out

    def apply(self, I: mi.Color3f, v: Vertex) -> mi.Color3f:
        """g_theta(I), branch-free on Dr.Jit arrays (dr.select, no `if` on array values).

        Args:
            I: the radiance estimate per lane (mi.Color3f); v: the vertices (`Vertex`).

        Returns:
            The styled colour per lane (mi.Color3f).
        """
        raise NotImplementedError

    def form(self):
        """g as an AffineForm, SeriesForm or PolynomialForm (see `forms`) for the unbiased
        estimators, or None where only direct application (and nothing unbiased) applies."""
        return None

    def step_thresholds(self, v: Vertex) -> tuple:
        """The brightnesses at which g jumps: the adaptive controller keeps drawing children while
        the mean's brightness is within a confidence band of one. Default: none (a continuous g).

        Args:
            v: the vertices (`Vertex`).

        Returns:
            A tuple of numbers or per-lane mi.Float (+inf: none at that lane).
        """
        return ()

    def curvature(self, I: mi.Color3f, v: Vertex, h: mi.Float) -> mi.Color3f:
        """g'' along the grey direction at I, d^2/dt^2 g(I + t (1, 1, 1)) per output channel, as
        the adaptive controller's smooth rule and the bias AOV (Eq. 21) use it. Default: 0 for an
        affine g (its form says so), else the central second difference over +-h: g''(I) for a
        smooth g, |jump of g'|/h at a kink (colour-map stops, clamps): the Jensen gap spread sees.

        Args:
            I: the children's mean (mi.Color3f); v: the vertices (`Vertex`).
            h: the children's standard error per lane (mi.Float), floored at 1e-4 max(u, 1).

        Returns:
            mi.Color3f.
        """
        from styletrace.styles.forms import AffineForm, CompositeForm
        form = self.form()
        if isinstance(form, AffineForm) or (isinstance(form, CompositeForm)
                                            and form.affine is not None):
            return mi.Color3f(0.0)
        # no 0/0 where the children agree
        h = dr.maximum(h, 1e-4 * dr.maximum(brightness(I), 1.0))
        return (self.apply(I + h, v) - 2.0 * self.apply(I, v) + self.apply(I - h, v)) / (h * h)

    def opaque(self, names=None) -> "Style":
        """A copy whose real-valued parameters are opaque Dr.Jit scalars, kernel inputs.

        A literal θ is part of the traced kernel and of its hash, so each new value compiles a
        new kernel (tens of milliseconds for a restyle, a second or more for a render's
        megakernel); an opaque one is an input the compiled kernel takes. Literals and inputs can
        round the last bit differently (LLVM folds constants). Design:
        docs/design/slider_restyles.md.

        Args:
            names: the parameters to make opaque (None: every one of a kind in OPAQUE_KINDS;
                others, and those of other kinds, stay as they are).

        Returns:
            The copy (float: one mi.Float of width 1; floats and color: a tuple of them);
            attributes that `prepare` set are shared with this style.
        """
        import copy
        out = copy.copy(self)
        out.values = dict(self.values)
        for p in self.params:
            value = self.values[p.name]
            if value is None or p.kind not in OPAQUE_KINDS or (names is not None
                                                               and p.name not in names):
                continue
            if p.kind == "float":
                out.values[p.name] = dr.opaque(mi.Float, float(value))
            else:
                out.values[p.name] = tuple(dr.opaque(mi.Float, float(x)) for x in value)
        return out

    def describe(self) -> str:
        vals = ", ".join(f"{p.name}={p.show(self.values[p.name])}" for p in self.params)
        return f"{self.name}({vals})"


def key_in(values: Mapping[str, Any], key: str) -> bool:
    """Whether a parameter is given a value.

    Args:
        values: parameter name -> value; key: the parameter's name.

    Returns:
        True where `key` is present and not None.
    """
    return key in values and values[key] is not None


@dataclass(frozen=True)
class Camera:
    """World-space frame of a scene's first sensor: position, unit forward (local +z) and up (local
    +y)."""

    position: tuple[float, float, float] = (0.0, 0.0, 0.0)
    forward: tuple[float, float, float] = (0.0, 0.0, 1.0)
    up: tuple[float, float, float] = (0.0, 1.0, 0.0)


def camera(scene: mi.Scene) -> Camera:
    """The frame of the scene's first sensor (Mitsuba's default frame if it has none).

    Args:
        scene: a loaded mi.Scene.

    Returns:
        The Camera (position, unit forward and up).
    """
    import numpy as np
    sensors = scene.sensors()
    if not sensors:
        return Camera()
    m = np.array(sensors[0].world_transform().matrix, dtype=np.float64).reshape(4, 4, -1)[..., 0]

    def unit(v):
        return tuple(float(x) for x in v / np.linalg.norm(v))
    return Camera(position=tuple(float(x) for x in m[:3, 3]), forward=unit(m[:3, 2]),
                  up=unit(m[:3, 1]))


@dataclass(frozen=True)
class Projection:
    """The first sensor's mapping of world points to screen pixels. A point p at camera depth
    z = (p - position) . forward spans `a z + b` scene units per pixel there (perspective: a = twice
    the tangent of half a pixel's angle, b = 0; orthographic: a = 0, b = the pixel's width)."""

    camera: Camera = Camera()
    right: tuple[float, float, float] = (1.0, 0.0, 0.0)
    #: until `projection(scene)` is read: a 45-degree field of view over 256 pixels
    a: float = 2.0 * 0.41421356237 / 256
    b: float = 0.0

    def footprint(self, p: mi.Point3f) -> tuple[mi.Vector3f, mi.Float]:
        """Where p lies from the camera, and its pixel size.

        Args:
            p: world points (mi.Point3f).

        Returns:
            (p - camera position as mi.Vector3f, the scene units per pixel at p's depth, mi.Float).
        """
        rel = mi.Vector3f(p - mi.Point3f(*self.camera.position))
        # points behind: finite, tiny
        z = dr.maximum(dr.dot(rel, mi.Vector3f(*self.camera.forward)), 1e-6)
        return rel, z * self.a + self.b

    def pixels(self, p: mi.Point3f) -> tuple[mi.Float, mi.Float]:
        """Screen coordinates of p in pixels along (`right`, camera up), relative to the image
        centre. `right` is cross(up, forward), which for a Mitsuba camera points towards the
        image's left (measured: film u = 0.9 gives a ray with x < 0; `kernel.anchors`).

        Args:
            p: world points (mi.Point3f).

        Returns:
            (x, y) in pixels, mi.Float each.
        """
        rel, fp = self.footprint(p)
        inv = dr.rcp(fp)
        return (dr.dot(rel, mi.Vector3f(*self.right)) * inv,
                dr.dot(rel, mi.Vector3f(*self.camera.up)) * inv)


def lanes(v, n: int):
    """A Dr.Jit 3-vector as a (3, n) float64 numpy array. A sensor returns a component that is the
    same for every lane as an array of width 1 (an orthographic sensor's ray direction, a
    perspective one's origin before the near-clip offset): it is repeated, so that lane k is ray k
    whatever the sensor type.

    Args:
        v: a Dr.Jit 3-vector of width n or 1; n: the lane count.

    Returns:
        numpy float64 (3, n), a read-only view.
    """
    import numpy as np
    a = np.array(v, dtype=np.float64).reshape(3, -1)
    return np.broadcast_to(a, (3, n))


def projection(scene: mi.Scene) -> Projection:
    """The first sensor's Projection, measured on the sensor itself: the rays through the film
    centre and one pixel to its right.

    Args:
        scene: a loaded mi.Scene.

    Returns:
        The Projection (the default one where the scene has no sensor).
    """
    import numpy as np
    sensors = scene.sensors()
    if not sensors:
        return Projection()
    cam = camera(scene)
    sensor = sensors[0]
    width = max(int(sensor.film().crop_size()[0]), 1)
    ray, _ = sensor.sample_ray(
        mi.Float(0.0),
        mi.Float(0.5),
        mi.Point2f([0.5, 0.5 + 1.0 / width], [0.5, 0.5]),
        mi.Point2f(0.5, 0.5),
    )
    d, o = lanes(ray.d, 2), lanes(ray.o, 2)
    f = np.array(cam.forward)
    a = float(np.linalg.norm(d[:, 1] / (d[:, 1] @ f) - d[:, 0] / (d[:, 0] @ f)))
    b = 0.0
    if a < 1e-12:  # parallel rays: orthographic
        a, b = 0.0, float(np.linalg.norm(o[:, 1] - o[:, 0]))
    up, fw = np.array(cam.up), f
    right = np.cross(up, fw)
    right /= np.linalg.norm(right)
    return Projection(camera=cam, right=tuple(float(x) for x in right), a=a, b=b)


def camera_forward(scene: mi.Scene) -> tuple[float, float, float]:
    """World-space viewing direction of the scene's first sensor.

    Args:
        scene: a loaded mi.Scene.

    Returns:
        The unit forward vector (x, y, z).
    """
    return camera(scene).forward


def rounded(x: float) -> float:
    """x to 4 significant digits: auto values are pinned as printed, so the printed line reproduces
    them.

    Args:
        x: the value.

    Returns:
        float(f"{x:.4g}").
    """
    return float(f"{x:.4g}")


def increasing(values) -> tuple[float, ...]:
    """Quantiles, rounded and made strictly increasing (ties, e.g. a scene of one brightness, are
    spread by a relative 1e-3, at least 1e-6), so that they are valid thresholds.

    Args:
        values: non-decreasing numbers.

    Returns:
        A strictly increasing tuple of `rounded` floats.
    """
    out: list[float] = []
    for x in values:
        x = rounded(x)
        if out and x <= out[-1]:
            x = rounded(out[-1] + max(abs(out[-1]) * 1e-3, 1e-6))
        out.append(x)
    return tuple(out)


#: The auto exposure of the tone styles (contrast, exp_tone, reinhard, gamma, tie_dye): the scene's
#: median first-hit brightness is scaled to photographic middle grey (the key value 0.18 of Reinhard
#: et al. 2002), so a scene ten times dimmer gets ten times the exposure and looks the same.
EXPOSURE_KEY = 0.18
#: Largest exposure. The unbiased series estimators take powers of exposed samples in float32: on
#: the Cornell box (light 18) series_recursive overflowed at exposure 1e3 and was finite at 1e2
#: (measured), so the auto rule stops here: a scene whose median brightness is below 0.18 / 100
#: comes out darker than middle grey.
MAX_EXPOSURE = 100.0


def exposure_param(what: str = "") -> Param:
    """The tone styles' `exposure` s: <I> is scaled by s before the tone curve (auto: see
    `auto_exposure`).

    Args:
        what: the auto rule's text; empty: the median rule of `auto_exposure`.

    Returns:
        The Param (float in (0, MAX_EXPOSURE], default auto).
    """
    return Param(
        "exposure",
        "float",
        None,
        "scale s of the expected radiance before the tone curve",
        low=0.0,
        low_open=True,
        high=MAX_EXPOSURE,
        auto=what
        or f"{EXPOSURE_KEY:g} / the median of the scene's first-hit brightness, at most "
        f"{MAX_EXPOSURE:g} (unresolved: 1)",
    )


def auto_exposure(facts, target: float = EXPOSURE_KEY, high: float = MAX_EXPOSURE) -> float:
    """`target` over the median first-hit brightness of what the style covers, at most `high`,
    rounded as printed.

    Args:
        facts: the style's `scene.defaults.Facts` (its `brightness([0.5])`).
        target: the brightness the median maps to (EXPOSURE_KEY; a style's pivot).
        high: the largest exposure.

    Returns:
        The exposure; NaN where the median or the target is not positive (a black scene, a pivot
        <= 0: the value is refused and the unresolved fallback applies).
    """
    (median,) = facts.brightness([0.5])
    if not (median > 0 and target > 0):
        return float("nan")
    return rounded(min(target / median, high))


def light_from_camera(cam: Camera) -> tuple[float, float, float]:
    """The 'auto' light direction of gooch and xtoon: the camera's up vector tilted a little towards
    the camera, normalize(up - 0.3 forward) (the old fixed default 0,1,0.3 for a y-up camera looking
    along -z).

    Args:
        cam: the scene's Camera.

    Returns:
        The unit direction, each component rounded to 4 decimals.
    """
    v = [u - 0.3 * f for u, f in zip(cam.up, cam.forward)]
    n = sum(x * x for x in v) ** 0.5
    return tuple(round(x / n, 4) for x in v)


__all__ = [
    "Style",
    "OPAQUE_KINDS",
    "Vertex",
    "Param",
    "StyleError",
    "brightness",
    "Camera",
    "camera",
    "camera_forward",
    "Projection",
    "projection",
    "lanes",
    "light_from_camera",
    "rounded",
    "increasing",
    "EXPOSURE_KEY",
    "MAX_EXPOSURE",
    "exposure_param",
    "auto_exposure",
]
