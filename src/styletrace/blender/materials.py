"""Blender materials -> Mitsuba BSDF descriptions (plain dicts, numpy images).

Supported behind the active Material Output: Principled BSDF (base colour from a value or an
Image Texture, roughness, IOR, Specular IOR Level and Specular Tint, metallic, transmission,
emission, alpha as a mask; Blender 3.x's node read by 4.x's names), Diffuse, Glossy, Glass and
Emission nodes; each node's mapping: `principled`, `convert_node`, docs/blender.md ("From the
depsgraph to Mitsuba", "Principled BSDF"). Every other node is named in one warning per export
and rendered as grey diffuse. Reflective BSDFs are wrapped in `twosided` (Cycles shades both
sides). A material with a styletrace style (`properties.MaterialSettings`) wraps its BSDF in a
`styled` BSDF. Design: docs/design/blender_export.md.
"""
from __future__ import annotations

import functools
from typing import Any, Callable

import numpy as np

GREY = (0.5, 0.5, 0.5)
#: Cycles' roughness is clamped below at this in its microfacet models; a smaller alpha is a mirror
SMOOTH = 1e-4


class MaterialContext:
    """What the exporter collects while converting materials: warnings (one per unsupported node
    type) and image textures (converted once per image).

    Args:
        warn: called with each warning line, at `flush`.
    """

    def __init__(self, warn: Callable[[str], None]):
        self.warn = warn
        self.unsupported: dict[str, list[str]] = {}
        self.images: dict[tuple[str, str], np.ndarray] = {}

    def unknown(self, node, material) -> None:
        """Note an unsupported node, named at `flush` once per node type.

        Args:
            node: the node. material: the material it is in.
        """
        self.unsupported.setdefault(node.bl_idname, []).append(material.name)

    def flush(self) -> None:
        for kind, mats in sorted(self.unsupported.items()):
            self.warn(
                f"styletrace: node {kind} is not supported (material "
                f"{', '.join(sorted(set(mats)))}): rendered as grey diffuse"
            )
        self.unsupported.clear()


def srgb_to_linear(x: np.ndarray) -> np.ndarray:
    """The sRGB transfer function undone.

    Args:
        x: sRGB values in [0, 1], a numpy array.

    Returns:
        Linear values, float32.
    """
    return np.where(x <= 0.04045, x / 12.92, ((x + 0.055) / 1.055) ** 2.4).astype(np.float32)


def image_array(image, ctx: MaterialContext, channel: str = "rgb") -> np.ndarray:
    """The image's pixels, top row first, linear (sRGB images decoded), converted once per image
    and channel.

    Args:
        image: the `bpy.types.Image`. ctx: the export's MaterialContext (its cache).
        channel: 'rgb' (H x W x 3) or 'alpha' (H x W x 1; 1 where the image has none).

    Returns:
        The float32 array.
    """
    key = (image.name, channel)
    if key not in ctx.images:
        w, h = image.size
        px = np.empty(w * h * image.channels, dtype=np.float32)
        image.pixels.foreach_get(px)
        px = px.reshape(h, w, image.channels)[::-1]  # Blender stores the bottom row first
        if channel == "alpha":
            out = px[..., 3:4] if image.channels == 4 else np.ones((h, w, 1), np.float32)
        else:
            rgb = px[..., :3] if image.channels >= 3 else np.repeat(px[..., :1], 3, axis=2)
            if image.colorspace_settings.name == "sRGB" and not image.is_float:
                rgb = srgb_to_linear(rgb)
            out = rgb
        ctx.images[key] = np.ascontiguousarray(out, dtype=np.float32)
    return ctx.images[key]


def texture(data: np.ndarray) -> dict:
    """A bitmap texture description; `data` stays a numpy array until the scene is built
    or written.

    Args:
        data: H x W x C float32, linear.

    Returns:
        The `bitmap` description (bilinear, repeat, raw).
    """
    return {
        "type": "bitmap",
        "data": data,
        "filter_type": "bilinear",
        "wrap_mode": "repeat",
        "raw": True,
    }


def _source(socket):
    if not socket.is_linked:
        return None
    link = socket.links[0]
    return link.from_node, link.from_socket


def colour(socket, ctx: MaterialContext, material) -> Any:
    """An RGB input: a constant, or an Image Texture node's colour; other nodes are reported.

    Args:
        socket: the input socket. ctx: the export's MaterialContext. material: the material.

    Returns:
        An `rgb` description, a `bitmap` texture, or grey for an unsupported node.
    """
    src = _source(socket)
    if src is None:
        return {"type": "rgb", "value": tuple(float(c) for c in socket.default_value[:3])}
    node, out = src
    if node.bl_idname == "ShaderNodeTexImage" and node.image is not None:
        return texture(image_array(node.image, ctx, "alpha" if out.name == "Alpha" else "rgb"))
    ctx.unknown(node, material)
    return {"type": "rgb", "value": GREY}


def scalar(socket, ctx: MaterialContext, material) -> float:
    """A scalar input's value; a linked node is reported, and the socket's own value used.

    Args:
        socket: the input socket. ctx: the export's MaterialContext. material: the material.

    Returns:
        The float.
    """
    src = _source(socket)
    if src is not None:
        ctx.unknown(src[0], material)
    return float(socket.default_value)


def alpha(roughness: float) -> float:
    """Mitsuba's microfacet alpha of a Blender roughness: its square, as in Cycles, at least SMOOTH.

    Args:
        roughness: Blender's roughness, in [0, 1].

    Returns:
        The alpha.
    """
    return max(roughness * roughness, SMOOTH)


def _conductor(color, roughness: float) -> dict:
    return {"type": "roughconductor", "material": "none", "specular_reflectance": color,
            "alpha": alpha(roughness), "distribution": "ggx"}


def _glass(color, roughness: float, ior: float) -> dict:
    ior = max(ior, 1.0 + 1e-4)
    return {"type": "roughdielectric", "int_ior": ior, "ext_ior": 1.0, "alpha": alpha(roughness),
            "distribution": "ggx", "specular_reflectance": color, "specular_transmittance": color}


def _blend(weight: float, a: dict, b: dict) -> dict:
    if weight <= 0:
        return a
    if weight >= 1:
        return b
    return {"type": "blendbsdf", "weight": weight, "a": a, "b": b}


def _unbounded(c: dict, k: float) -> float | dict:
    # a colour times k, where the product may exceed 1: Mitsuba refuses an `rgb` reflectance
    # above 1, not a float or a raw bitmap
    if c.get("type") != "rgb":
        return texture(c["data"] * np.float32(k))
    value = np.asarray(c["value"], dtype=np.float32) * np.float32(k)
    if np.all(value == value[0]):
        return float(value[0])
    return texture(value.reshape(1, 1, 3))


def fresnel_dielectric(cos: np.ndarray, eta: float) -> np.ndarray:
    """Unpolarised Fresnel reflectance of light arriving from outside a dielectric.

    Args:
        cos: cosines of the angle of incidence, in (0, 1]. eta: the relative IOR, > 1.

    Returns:
        The reflectances, an array shaped as `cos`.
    """
    g = np.sqrt(eta * eta - 1.0 + cos * cos)
    a = (g - cos) / (g + cos)
    b = (cos * (g + cos) - 1.0) / (cos * (g - cos) + 1.0)
    return 0.5 * a * a * (1.0 + b * b)


#: quadrature of the specular layer's albedo: Gauss-Legendre nodes in cos(theta) on (0, 1), and a
#: midpoint grid of the unit square for the visible normals (within 0.07% of a 64-node,
#: 128 x 128 quadrature)
_MU_NODES, _VNDF_GRID = 16, 32


@functools.lru_cache(maxsize=256)
def specular_layer(alpha: float, eta: float) -> tuple[float, float]:
    """(albedo, compensation) of Cycles' dielectric specular layer: GGX of `alpha` with the
    Fresnel reflectance of `eta`, times Cycles' multiple-scattering compensation
    1 + Fms (1 - E1) / E1 (E1: the albedo with Fresnel 1; Fms from the mean Fresnel Fss and the
    mean E1, as Kulla and Conty).

    Cycles' Principled BSDF darkens the diffuse layer under it by 1 - (the layer's albedo in the
    view direction); the albedo here is its cosine-weighted mean over the hemisphere, which is
    what diffuse light averages to. The compensation is the ratio of the compensated mean albedo
    to the single-scattering one.

    Args:
        alpha: the GGX alpha (roughness squared). eta: the IOR the Fresnel term uses, > 1.

    Returns:
        The mean albedo in [0, 1), and the compensation factor >= 1.
    """
    x, w = np.polynomial.legendre.leggauss(_MU_NODES)
    mu, w = 0.5 * (x + 1.0), 0.5 * w
    u = (np.arange(_VNDF_GRID) + 0.5) / _VNDF_GRID
    u1, u2 = (a.ravel() for a in np.meshgrid(u, u, indexing="ij"))
    sin = np.sqrt(1.0 - mu * mu)
    # Heitz's sampling of the visible normals, viewed from (sin, 0, mu): the view stretched
    # to the hemisphere configuration, a disk sample warped onto the visible half
    vh = np.stack([alpha * sin, np.zeros_like(mu), mu], axis=1)
    vh /= np.linalg.norm(vh, axis=1, keepdims=True)
    t1 = np.array([0.0, 1.0, 0.0])  # the views lie in the xz plane: t1 is normal to each
    t2 = np.cross(vh, t1)
    r, phi = np.sqrt(u1), 2.0 * np.pi * u2
    p1 = r * np.cos(phi)
    s = 0.5 * (1.0 + vh[:, 2:3])
    p2 = (1.0 - s) * np.sqrt(1.0 - p1 * p1) + s * (r * np.sin(phi))
    p3 = np.sqrt(np.maximum(0.0, 1.0 - p1 * p1 - p2 * p2))
    nh = p1[..., None] * t1 + p2[..., None] * t2[:, None] + p3[..., None] * vh[:, None]
    m = nh * np.array([alpha, alpha, 1.0])
    m[..., 2] = np.maximum(m[..., 2], 1e-7)
    m /= np.linalg.norm(m, axis=2, keepdims=True)
    v = np.stack([sin, np.zeros_like(mu), mu], axis=1)
    vm = np.einsum("nsk,nk->ns", m, v)
    out_z = 2.0 * vm * m[..., 2] - mu[:, None]  # the reflected direction's cosine

    def smith_lambda(c):
        c = np.clip(c, 1e-7, 1.0)
        return 0.5 * (np.sqrt(1.0 + alpha * alpha * (1.0 / (c * c) - 1.0)) - 1.0)

    lam_v = smith_lambda(mu)[:, None]
    # a sample weighs G2 / G1(view); below the horizon it is lost
    g = np.where(out_z > 0, (1.0 + lam_v) / (1.0 + lam_v + smith_lambda(out_z)), 0.0)
    e1 = g.mean(axis=1)
    ef = (g * fresnel_dielectric(vm, eta)).mean(axis=1)
    mean = lambda f: float(np.sum(2.0 * mu * w * f))  # noqa: E731
    fss, e1_avg = mean(fresnel_dielectric(mu, eta)), mean(e1)
    fms = fss * e1_avg / (1.0 - fss * (1.0 - e1_avg))
    ef_mean = mean(ef)
    albedo = mean(ef * (1.0 + fms * (1.0 - e1) / e1))
    return albedo, albedo / ef_mean


def _dielectric(base, tint, roughness: float, f0: float) -> dict:
    # Cycles lays a GGX dielectric of normal reflectance f0 over a Lambertian base and darkens
    # the base by the layer's albedo; Mitsuba's roughplastic models a physical layer instead
    # (the 1/eta^2 of the radiance entering the coat, internal reflections, a transmittance
    # on both sides), 1.5 to 6 times darker than Cycles in a closed room. Here: a blend of the
    # base and the layer, weighted by the layer's mean albedo (`specular_layer`); the layer's
    # Fresnel is a conductor's of the real IOR eta with k = 0, i.e. the dielectric's.
    sqrt_f0 = np.sqrt(min(f0, 0.99))  # Cycles' ior_from_F0 clamps F0 at 0.99 too
    eta = float((1.0 + sqrt_f0) / (1.0 - sqrt_f0))
    a = alpha(roughness)
    albedo, compensation = specular_layer(a, eta)
    layer = {"type": "roughconductor", "eta": eta, "k": 0.0, "alpha": a, "distribution": "ggx",
             "specular_reflectance": _unbounded(tint, compensation / albedo)}
    return _blend(albedo, {"type": "diffuse", "reflectance": base}, layer)


#: Blender 3.x's names of the Principled BSDF inputs that 4.0 renamed, by 4.x's name
PRINCIPLED_3X_NAMES = {"Specular IOR Level": "Specular", "Transmission Weight": "Transmission",
                       "Emission Color": "Emission"}
#: the IOR at which 4.x's F0 = ((IOR - 1) / (IOR + 1))^2 x 2 x level is 3.x's 0.08 x Specular
PRINCIPLED_3X_IOR = 1.5
#: Rec. 709 luminance of linear RGB: Cycles' `linear_rgb_to_gray` in Blender's default colour space
LUMA = (0.2126, 0.7152, 0.0722)


def principled_3x_tint(tint: float, base: dict) -> dict:
    """Blender 3.x's Specular Tint (a float) as 4.x's colour: 3.x's F0 colour is
    (1 - tint) + tint x Base Color / its luminance (white where that is 0), as Cycles 3.x's.

    Args:
        tint: the 3.x input's value, in [0, 1]. base: Base Color's description (`colour`).

    Returns:
        An `rgb` description, or a `bitmap` texture where Base Color is one.
    """
    if base.get("type") == "rgb":
        c = np.asarray(base["value"], dtype=np.float64)
        lum = float(np.dot(c, LUMA))
        hue = c / lum if lum > 0 else np.ones(3)
        return {"type": "rgb", "value": tuple(float(v) for v in (1.0 - tint) + tint * hue)}
    data = base["data"]
    lum = data @ np.asarray(LUMA, dtype=np.float32)
    hue = np.where(lum[..., None] > 0, data / np.maximum(lum, 1e-30)[..., None], 1.0)
    return texture(((1.0 - tint) + tint * hue).astype(np.float32))


def principled_sockets(node) -> tuple[Callable[[str], Any], float | None]:
    """The Principled BSDF's inputs by Blender 4.x's names, for 4.x's node and for 3.x's.

    Blender 3.x names three of the inputs `principled` reads otherwise (`PRINCIPLED_3X_NAMES`),
    its Specular Tint is a float (`principled_3x_tint`), and its specular layer's F0 is
    0.08 x Specular whatever the IOR, which 4.x's formula gives at IOR 1.5 with level = Specular;
    3.x's IOR sets the transmission's refraction only. A 3.x node is one without "Specular IOR
    Level".

    Args:
        node: the Principled BSDF node (anything with `inputs[name]` and `inputs.get(name)`).

    Returns:
        (socket by 4.x name, the IOR of F0: None for a 4.x node, whose IOR input it is;
        `PRINCIPLED_3X_IOR` for a 3.x node).
    """
    inputs = node.inputs
    if inputs.get("Specular IOR Level") is not None:
        return inputs.__getitem__, None
    return (lambda name: inputs[PRINCIPLED_3X_NAMES.get(name, name)]), PRINCIPLED_3X_IOR


def principled(node, ctx: MaterialContext, material) -> tuple[dict, dict | None, Any]:
    """(bsdf, emitter or None, opacity) of a Principled BSDF node.

    A dielectric base as Cycles': a Lambertian `diffuse` of Base Color under a GGX specular layer
    whose normal reflectance is F0 = ((IOR - 1) / (IOR + 1))^2 x 2 x Specular IOR Level. Cycles
    darkens the diffuse by the layer's albedo in the view direction, which no Mitsuba BSDF does;
    here the two are a `blendbsdf` weighted by the layer's mean albedo (`specular_layer`): the
    diffuse keeps 1 - that albedo of Base Color, and the layer (a `roughconductor` with the
    dielectric's Fresnel, k = 0) all of its own, times Cycles' mean multiple-scattering
    compensation and Specular Tint (which tints the whole layer; Cycles tints F0 only). `diffuse`
    alone where F0 = 0. That base is blended with a `roughdielectric` by Transmission Weight and
    a `roughconductor` (Fresnel taken as 1, as Cycles' F82 at normal incidence) by Metallic;
    emission colour x strength as an `area` emitter. Blender 3.x's node is read by 4.x's names
    and meaning (`principled_sockets`).

    Args:
        node: the node. ctx: the export's MaterialContext. material: the material.

    Returns:
        The BSDF, the emitter or None, and the opacity (a float, or a texture of the Alpha input).
    """
    inp, f0_ior = principled_sockets(node)
    base = colour(inp("Base Color"), ctx, material)
    rough = scalar(inp("Roughness"), ctx, material)
    metal = scalar(inp("Metallic"), ctx, material)
    trans = scalar(inp("Transmission Weight"), ctx, material)
    ior = scalar(inp("IOR"), ctx, material)
    level = scalar(inp("Specular IOR Level"), ctx, material)
    eta = ior if f0_ior is None else f0_ior
    f0 = ((eta - 1.0) / (eta + 1.0)) ** 2 * 2.0 * max(level, 0.0)
    if f0 <= 0:
        bsdf = {"type": "diffuse", "reflectance": base}
    else:
        if f0_ior is None:
            tint = colour(inp("Specular Tint"), ctx, material)
        else:
            tint = principled_3x_tint(scalar(inp("Specular Tint"), ctx, material), base)
        bsdf = _dielectric(base, tint, rough, f0)
    bsdf = _blend(trans, bsdf, _glass(base, rough, ior))
    bsdf = _blend(metal, bsdf, _conductor(base, rough))
    strength = scalar(inp("Emission Strength"), ctx, material)
    emitter = None
    if strength > 0:
        e = colour(inp("Emission Color"), ctx, material)
        if e.get("type") == "rgb":
            e = {"type": "rgb", "value": tuple(c * strength for c in e["value"])}
            emitter = {"type": "area", "radiance": e} if any(e["value"]) else None
        else:
            emitter = {"type": "area", "radiance": texture(e["data"] * np.float32(strength))}
    a_src = _source(inp("Alpha"))
    opacity = colour(inp("Alpha"), ctx, material) if a_src else float(inp("Alpha").default_value)
    return bsdf, emitter, opacity


def convert_node(node, ctx: MaterialContext, material) -> tuple[dict, dict | None, Any]:
    """(bsdf, emitter or None, opacity) of the shader node feeding a Material Output.

    Glossy: `roughconductor` without Fresnel, tinted by its colour; Glass: `roughdielectric` with
    the IOR, both lobes tinted; Emission: an `area` emitter of colour x strength, a black surface.

    Args:
        node: the shader node. ctx: the export's MaterialContext. material: the material.

    Returns:
        The descriptions; an unsupported node is reported and gives grey diffuse.
    """
    kind = node.bl_idname
    inp = node.inputs
    if kind == "ShaderNodeBsdfPrincipled":
        return principled(node, ctx, material)
    if kind == "ShaderNodeBsdfDiffuse":
        return {"type": "diffuse", "reflectance": colour(inp["Color"], ctx, material)}, None, 1.0
    if kind in ("ShaderNodeBsdfGlossy", "ShaderNodeBsdfAnisotropic"):
        return (
            _conductor(
                colour(inp["Color"], ctx, material), scalar(inp["Roughness"], ctx, material)
            ),
            None,
            1.0,
        )
    if kind == "ShaderNodeBsdfGlass":
        return (_glass(colour(inp["Color"], ctx, material), scalar(inp["Roughness"], ctx, material),
                       scalar(inp["IOR"], ctx, material)), None, 1.0)
    if kind == "ShaderNodeEmission":
        c = colour(inp["Color"], ctx, material)
        s = scalar(inp["Strength"], ctx, material)
        radiance = (
            {"type": "rgb", "value": tuple(v * s for v in c["value"])}
            if c.get("type") == "rgb"
            else texture(c["data"] * np.float32(s))
        )
        return {"type": "diffuse", "reflectance": {"type": "rgb", "value": (0.0, 0.0, 0.0)}}, \
            {"type": "area", "radiance": radiance}, 1.0
    ctx.unknown(node, material)
    return grey(), None, 1.0


def grey() -> dict:
    return {"type": "diffuse", "reflectance": {"type": "rgb", "value": GREY}}


def _transmits(bsdf: dict) -> bool:
    if bsdf["type"] in ("roughdielectric", "dielectric", "thindielectric"):
        return True
    return any(
        _transmits(v)
        for v in bsdf.values()
        if isinstance(v, dict)
        and "type" in v
        and v is not bsdf
        and v["type"] not in ("rgb", "bitmap")
    )


def output_node(material):
    """The material's Material Output: the active one for all renderers or Cycles, else the first.

    Args:
        material: the `bpy.types.Material`.

    Returns:
        The node, or None without a node tree or an output.
    """
    tree = material.node_tree
    if tree is None:
        return None
    outputs = [n for n in tree.nodes if n.bl_idname == "ShaderNodeOutputMaterial"]
    for n in outputs:
        if n.is_active_output and n.target in ("ALL", "CYCLES"):
            return n
    return outputs[0] if outputs else None


def convert_material(
    material, ctx: MaterialContext, style: dict | None = None
) -> tuple[dict, dict | None]:
    """(bsdf, emitter or None) of a Blender material.

    Args:
        material: the material (None: grey diffuse). ctx: the export's MaterialContext.
        style: the material's styletrace settings as `styled` properties (None: no style).

    Returns:
        The BSDF (twosided unless it transmits, in a `styled` BSDF with a style, in a `mask` where
        the opacity is below 1 or textured) and the `area` emitter or None.
    """
    if material is None:
        bsdf, emitter, opacity = grey(), None, 1.0
    else:
        out = output_node(material)
        src = _source(out.inputs["Surface"]) if out is not None else None
        if src is None:
            # no node tree (or nothing connected): Blender's viewport colour, as Cycles renders an
            # unlinked output black
            bsdf, emitter, opacity = (
                {
                    "type": "diffuse",
                    "reflectance": {
                        "type": "rgb",
                        "value": tuple(float(c) for c in material.diffuse_color[:3]),
                    },
                },
                None,
                1.0,
            )
            if out is not None:
                bsdf = {"type": "diffuse", "reflectance": {"type": "rgb", "value": (0.0, 0.0, 0.0)}}
        else:
            bsdf, emitter, opacity = convert_node(src[0], ctx, material)
    if not _transmits(bsdf):
        # Cycles shades both sides of a surface; Mitsuba's reflective BSDFs are one-sided
        bsdf = {"type": "twosided", "nested": bsdf}
    if style:
        bsdf = {"type": "styled", **style, "nested": bsdf}
    if isinstance(opacity, dict) or opacity < 1.0:
        op = opacity if isinstance(opacity, dict) else {"type": "rgb", "value": (opacity,) * 3}
        if isinstance(op, dict) and op.get("type") == "bitmap" and op["data"].shape[-1] == 3:
            op = texture(np.ascontiguousarray(op["data"].mean(axis=2, keepdims=True)))
        bsdf = {"type": "mask", "opacity": op, "nested": bsdf}
    return bsdf, emitter
