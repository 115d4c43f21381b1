"""Blender properties generated from styletrace's registries: no hand-written list of styles
or parameters.

`StyleParams` holds one Blender property per (style, parameter) of the style registry, named
`<style>__<parameter>`, typed by the parameter's kind (float, int, bool, colour, choice; lists,
gradients and 'auto' defaults are strings in the spelling `--set` takes). The render settings
(`SceneSettings`) and each material's settings (`MaterialSettings`) carry a style name and one
`StyleParams`; panels draw the parameters of the chosen style only. Values go to styletrace as
given, so the registry (`Param.parse`) is the one judge of what is allowed; its refusals reach the
user as one-line Blender error reports (engine, operators).
"""
from __future__ import annotations

import math

import bpy

# first: the plugins are registered before the registries below load (blender/registered.py)
from styletrace.blender.registered import VARIANT  # noqa: F401
from styletrace.config import estimator_registry
from styletrace.config import settings as S
from styletrace.config.choices import SAMPLER_DEFAULT
from styletrace.denoise.oidn import QUALITIES
from styletrace.pipeline.denoising import default_method
from styletrace.styles import registry

SEP = "__"


def key(style: str, param: str) -> str:
    """The StyleParams property name of a style's parameter, `<style>__<parameter>`.

    Args:
        style: the style's name. param: the parameter's name.

    Returns:
        The name.
    """
    return f"{style}{SEP}{param}"


def _finite(x):
    return x is not None and math.isfinite(x)


def blender_property(p):
    """The bpy property declaring style parameter `p`; its update calls `changed`.

    Args:
        p: a `styles.params.Param`.

    Returns:
        A Float, Int, Bool, FloatVector (colour) or Enum property, or a String property for lists,
        gradients, vectors and 'auto' defaults.

    Raises:
        AssertionError: a parameter kind without a Blender property.
    """
    text = p.explain()[:400]
    if p.default is None or p.kind in ("floats", "gradient", "vector"):
        return bpy.props.StringProperty(name=p.name, description=text + f" ({p.allowed()})",
                                        default=p.show(p.default), update=changed)
    lo, hi = p.bounds()
    if p.kind == "float":
        kw = {"min": lo} if _finite(lo) else {}
        kw.update({"max": hi} if _finite(hi) else {})
        return bpy.props.FloatProperty(
            name=p.name, description=text, default=p.default, update=changed, **kw
        )
    if p.kind == "int":
        kw = {"min": int(lo)} if _finite(lo) else {}
        kw.update({"max": int(hi)} if _finite(hi) else {})
        return bpy.props.IntProperty(
            name=p.name, description=text, default=p.default, update=changed, **kw
        )
    if p.kind == "bool":
        return bpy.props.BoolProperty(
            name=p.name, description=text, default=p.default, update=changed
        )
    if p.kind == "color":
        return bpy.props.FloatVectorProperty(
            name=p.name,
            description=text,
            default=p.default,
            size=3,
            subtype="COLOR",
            min=0.0,
            update=changed,
        )
    if p.kind == "choice":
        return bpy.props.EnumProperty(
            name=p.name,
            description=text,
            items=[(c, c, "") for c in p.choices],
            default=p.default,
            update=changed,
        )
    raise AssertionError(f"no Blender property for parameter kind {p.kind}")


def style_items():
    return [(n, n, registry.style_class(n).summary[:200]) for n in registry.style_names()]


#: called with the context when a style setting changes (`restyle` registers its restyling here)
ON_CHANGE: list = []


def changed(self, context):
    """A style setting changed: tell the listeners (restyling from the recorded buffer, if there
    is one).

    Args:
        self: the property group. context: Blender's context, passed to each of ON_CHANGE.
    """
    for listener in ON_CHANGE:
        listener(context)


def _annotations() -> dict:
    return {
        key(n, p.name): blender_property(p)
        for n in registry.style_names()
        for p in registry.style_class(n).params
    }


StyleParams = type(
    "StyleParams",
    (bpy.types.PropertyGroup,),
    {"__annotations__": _annotations(), "__doc__": "Every registered style's parameters"},
)


def params_of(style: str, params) -> dict:
    """{parameter: value} of `style` from a StyleParams, in forms `Param.parse` and Mitsuba
    properties take (colours as "r,g,b").

    Args:
        style: the style's name. params: the StyleParams.

    Returns:
        The values.
    """
    out = {}
    for p in registry.style_class(style).params:
        v = getattr(params, key(style, p.name))
        if p.kind == "color":
            v = ",".join(f"{c:g}" for c in v)
        out[p.name] = v
    return out


def _enum(names):
    return [(n, n, "") for n in names]


class SceneSettings(bpy.types.PropertyGroup):
    """The render settings of the styletrace engine (the `stylized` integrator's properties)."""

    style: bpy.props.EnumProperty(
        name="Style", items=style_items(), default="identity", update=changed
    )
    params: bpy.props.PointerProperty(type=StyleParams)
    inner_samples: bpy.props.StringProperty(
        name="Inner samples",
        default="",
        update=changed,
        description="n: child estimates per stylized vertex ('8', '8,4' per level, '4:64' "
        "adaptive); empty: the style's default",
    )
    estimator: bpy.props.EnumProperty(
        name="Estimator", items=_enum(estimator_registry.estimator_names()), default="direct",
        update=changed
    )
    stylize: bpy.props.EnumProperty(
        name="Stylize", items=_enum(S.STYLIZE_MODES), default="first_hit"
    )
    stylize_depth: bpy.props.IntProperty(
        name="Stylize depth", default=1, min=1, max=S.MAX_STYLIZE_DEPTH
    )
    lines: bpy.props.BoolProperty(
        name="Lines",
        default=False,
        description="physically based feature lines; adds a line mask pass",
    )
    line_mode: bpy.props.EnumProperty(
        name="Line mode",
        items=_enum(S.LINE_MODES),
        default="absorb",
        description="absorb: West 2021's cone along the path; lifted: LLaT's conditional lifting, "
        "one auxiliary path pair per line type, lines that keep their screen width in mirrors and "
        "glass",
    )
    line_types: bpy.props.StringProperty(
        name="Line types",
        default="",
        description="lifted mode: the line dictionary in priority order, e.g. 'shape_id "
        "color=1,0,0; depth threshold=0.05; normal threshold=0.5'; empty: styletrace's default",
    )
    reuse: bpy.props.EnumProperty(name="Reuse", items=_enum(S.REUSE_MODES), default="off")
    samples: bpy.props.IntProperty(
        name="Samples",
        default=16,
        min=1,
        description="paths per pixel, the render's cost whatever the style (as Cycles' Samples): "
        "split into camera samples x children (`styletrace render --samples`; docs/look.md)",
    )
    spp: bpy.props.IntProperty(
        name="Camera samples",
        default=0,
        min=0,
        description="camera samples per pixel, each with Inner samples children; 0: auto, from "
        "Samples (with Inner samples given too, the two set the cost and Samples is not used)",
    )
    pass_spp: bpy.props.IntProperty(
        name="Camera samples per pass",
        default=1,
        min=1,
        description="camera samples per pixel in one pass: cancel, progress and the viewport's "
        "images act between passes; the same seed and split give the same image "
        "(`styletrace render --pass-spp`). With the Owen-scrambled Sobol pattern F12's passes "
        "start here and double, up to the pass loop's size (the image does not depend on the "
        "split)",
    )
    sampler: bpy.props.EnumProperty(
        name="Sampling pattern",
        default=SAMPLER_DEFAULT,
        items=[
            ("owen_sobol", "Owen-scrambled Sobol",
             "a low-discrepancy sequence over each pixel's samples, every child of a stylized "
             "vertex on a stream of its own (docs/design/sequence_sampler.md)"),
            ("independent", "Independent",
             "independent random numbers for every sample: the paper's protocols; the error "
             "passes' Variance is then exact (with the sequence it is an upper bound)"),
        ],
        description="where the samples' random numbers come from (the scene's `sampler`)",
    )
    max_depth: bpy.props.IntProperty(name="Max depth", default=-1, min=-1)
    seed: bpy.props.IntProperty(name="Seed", default=0, min=0)
    aovs: bpy.props.BoolProperty(name="Error passes", default=True,
                                 description="variance, bias and children render passes")
    record_buffer: bpy.props.BoolProperty(
        name="Record buffer",
        default=False,
        description="keep the look-development buffer of the last render; style changes then "
                    "restyle it",
    )
    temporal_reuse: bpy.props.BoolProperty(
        name="Temporal reuse",
        default=True,
        description="Render Animation, denoised: the frames of a still shot accumulate the "
                    "estimate the denoiser meets, so they converge and settle; any change to the "
                    "scene or the settings starts again (docs/temporal.md)",
    )
    denoise: bpy.props.EnumProperty(
        name="Denoise",
        default=default_method(),
        items=[
            (
                "auto",
                "Auto",
                "expectation for a style of several children where it applies, else image, else "
                "off with a warning; with the firefly control: every front end's default "
                "(docs/look.md)",
            ),
            ("off", "Off", "no denoising: the paper's estimators exactly"),
            (
                "expectation",
                "Expectation",
                "denoise the expectation at the stylized vertex, then apply the "
                "style: step styles stay free of band flips (docs/denoise.md)",
            ),
            ("image", "Image", "denoise the final image, as an ordinary renderer does"),
        ],
        description="OIDN with albedo and normal guides (the 'denoise' extra); error passes are "
        "off while it is on, and a Noisy pass keeps the image before denoising",
    )
    denoise_quality: bpy.props.EnumProperty(name="Denoise quality", items=_enum(QUALITIES),
                                            default="high")
    denoise_footprint: bpy.props.EnumProperty(
        name="Image denoiser's input", default="pixel",
        items=[("pixel", "Pixel", "each pixel's own samples, the film's filter applied after "
                "(docs/look.md)"),
               ("film", "Film", "the film's image as it is: a tent or gaussian filter's "
                "correlated noise survives OIDN (the denoiser before)")],
        description="what Denoise 'image' denoises (`denoise_footprint`)")
    firefly: bpy.props.EnumProperty(
        name="Firefly control", default="auto",
        items=[("auto", "Auto", "on where the render is denoised, else off (docs/look.md)"),
               ("off", "Off", "the paper's estimator: every child as it is"),
               ("on", "On", "cap the brightest child at k times the others' mean brightness")],
        description="the firefly control at the stylized vertex (`firefly`)")
    firefly_k: bpy.props.FloatProperty(
        name="Firefly k",
        default=4.0,
        min=1.0,
        description="the cap, in units of the other children's mean brightness",
    )


class MaterialSettings(bpy.types.PropertyGroup):
    """A material's own style: the material's BSDF becomes a `styled` BSDF."""

    use_style: bpy.props.BoolProperty(name="Style this material", default=False)
    style: bpy.props.EnumProperty(name="Style", items=style_items(), default="cel", update=changed)
    params: bpy.props.PointerProperty(type=StyleParams)
    inner_samples: bpy.props.StringProperty(name="Inner samples", default="", update=changed)
    estimator: bpy.props.EnumProperty(
        name="Estimator", items=_enum(estimator_registry.estimator_names()), default="direct"
    )


def style_values(settings) -> dict:
    """The `styled` BSDF's (or integrator's style slot's) properties of a settings group.

    Args:
        settings: a SceneSettings or MaterialSettings.

    Returns:
        style, its parameters, and inner_samples and estimator where they are not the defaults.
    """
    out = {"style": settings.style, **params_of(settings.style, settings.params)}
    if settings.inner_samples.strip():
        out["inner_samples"] = settings.inner_samples.strip()
    if settings.estimator != "direct":
        out["estimator"] = settings.estimator
    return out


def settings_integrator_values(settings) -> dict:
    """The `stylized` integrator's properties from the render settings.

    Args:
        settings: the scene's SceneSettings.

    Returns:
        The style values, stylize, stylize_depth, lines, reuse and max_depth, and where set
        firefly, line_mode and line_types.
    """
    out = style_values(settings)
    out.update(stylize=settings.stylize, stylize_depth=settings.stylize_depth, lines=settings.lines,
               reuse=settings.reuse, max_depth=settings.max_depth)
    if settings.firefly != "auto":
        out["firefly"] = 0.0 if settings.firefly == "off" else float(settings.firefly_k)
    if settings.lines:
        out["line_mode"] = settings.line_mode
        if settings.line_types.strip():
            out["line_types"] = settings.line_types.strip()
    return out


CLASSES = (StyleParams, SceneSettings, MaterialSettings)


def register_properties():
    for cls in CLASSES:
        bpy.utils.register_class(cls)
    bpy.types.Scene.styletrace = bpy.props.PointerProperty(type=SceneSettings)
    bpy.types.Material.styletrace = bpy.props.PointerProperty(type=MaterialSettings)


def unregister_properties():
    del bpy.types.Material.styletrace
    del bpy.types.Scene.styletrace
    for cls in reversed(CLASSES):
        bpy.utils.unregister_class(cls)
