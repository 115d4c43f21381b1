"""The scene-feature regression corpus (issue 18): small Mitsuba 3 XML scenes written by the tests.

Every scene is generated here, assets included (textures written with numpy and `mi.Bitmap`, meshes
as PLY text, volumes with `mi.VolumeGrid`): nothing is downloaded. Each is a 32 x 32 image with a
box filter (pixels are then independent estimates, which the per-pixel tests assume) and its own
Mitsuba integrator with its `max_depth`; `<default name="spp">` sets the sampler's count.

Interface:
- `SCENES`: the scene names, in order.
- `write_scene(name, folder) -> Path`: writes the XML and its assets into `folder`, returns the
  XML's path.
- `REFERENCE_INTEGRATOR[name]`: Mitsuba's own integrator of the scene as a `mi.load_dict` dict,
  *unwrapped* (the scene file may wrap it in `moment` or `aov`; the plain integrator is what its
  image means). `max_depth` is given explicitly wherever the integrator has one, so a negative
  control can change it.
- `FEATURES[name]`: the features the scene covers (for reports and the corpus figure).
- `BY_DEFAULT`: the scenes that pick their integrator's type through a `<default>` parameter,
  Mitsuba's own convention (`<default name="integrator" value="direct"/>` and `<integrator
  type="$integrator">`).

Which scene covers what:
- textured: diffuse bitmap (PNG) texture, textured roughness on a textured `roughconductor`, a
  textured `principled` on a PLY mesh without normals (Mitsuba computes its vertex normals), an area
  and a point light.
- envmap: an EXR environment map (`envmap`) lighting `roughdielectric`, `thindielectric`,
  `roughplastic`, `twosided` and a textured-weight `blendbsdf`.
- normal_bump: `normalmap` (EXR, raw) and `bumpmap` (PNG), lit by a spot and a directional light.
- instances: `shapegroup` + `instance`, a `styled` BSDF inside one instanced group, a `projector`
  light, an orthographic sensor, the integrator wrapped in `moment`.
- colours: per-vertex and per-face colours (`mesh_attribute`), a thin-lens sensor, `aov`-wrapped
  `path`.
- direct: the `direct` integrator with hidden emitters (`hide_emitters`).
- direct_default: a sphere floating over a plane under a directional light, the `direct` integrator
  picked as Mitsuba's test scenes pick it (`type="$integrator"`): the sphere's underside and the
  shadow are black.
- ptracer: the `ptracer` light tracer on a diffuse scene.
- medium_light: a homogeneous medium with an area light and an object inside it (`volpath`).
- smoke_env: a heterogeneous `gridvolume` medium with an albedo volume inside a `null` boundary,
  under an EXR environment map (`volpath`).
"""
from __future__ import annotations

import math
import pathlib

import numpy as np

RES = 32

# Mitsuba's own integrator of each scene (unwrapped) and the wrapper the scene file puts around it.
REFERENCE_INTEGRATOR: dict[str, dict] = {
    "textured": {"type": "path", "max_depth": 5},
    "envmap": {"type": "path", "max_depth": 8},
    "normal_bump": {"type": "path", "max_depth": 4},
    "instances": {"type": "path", "max_depth": 4},
    "colours": {"type": "path", "max_depth": 3},
    # no max_depth: direct is depth 2 by definition
    "direct": {"type": "direct", "hide_emitters": True},
    "direct_default": {"type": "direct"},
    "ptracer": {"type": "ptracer", "max_depth": 4},
    "medium_light": {"type": "volpath", "max_depth": 8},
    "smoke_env": {"type": "volpath", "max_depth": 6},
}
WRAPPER: dict[str, str] = {"instances": "moment", "colours": "aov"}
BY_DEFAULT: set[str] = {"direct_default"}
SCENES: list[str] = list(REFERENCE_INTEGRATOR)

FEATURES: dict[str, str] = {
    "textured": "PNG bitmap, textured roughness, textured roughconductor, textured principled, "
    "PLY without "
    "normals, area + point light",
    "envmap": "EXR envmap, roughdielectric, thindielectric, roughplastic, twosided, blendbsdf",
    "normal_bump": "normalmap, bumpmap, spot + directional light",
    "instances": "shapegroup + instance, styled BSDF in a group, projector light, orthographic "
    "sensor, moment",
    "colours": "per-vertex and per-face colours (mesh_attribute), thin-lens sensor, aov",
    "direct": "direct integrator, hide_emitters",
    "direct_default": "integrator type from a default ($integrator = direct), directional light, "
    "floating sphere",
    "ptracer": "ptracer (light tracer)",
    "medium_light": "homogeneous medium with an area light and an object inside (volpath)",
    "smoke_env": "heterogeneous gridvolume + albedo volume, null boundary, EXR envmap (volpath)",
}


# ----------------------------------------------------------------------------------------------
# assets

def _bitmap(path: pathlib.Path, array: np.ndarray) -> str:
    """Write an image (uint8 for PNG, float32 for EXR) with Mitsuba's own writer; return its file
    name."""
    import mitsuba as mi
    mi.Bitmap(np.ascontiguousarray(array)).write(str(path))
    return path.name


def _checker(path, n=8, size=64, a=(0.8, 0.75, 0.7), b=(0.15, 0.3, 0.6)):
    i, j = np.meshgrid(np.arange(size), np.arange(size), indexing="ij")
    odd = ((i * n // size + j * n // size) % 2)[..., None]
    rgb = np.where(odd == 1, np.array(b), np.array(a))
    return _bitmap(path, (rgb * 255).astype(np.uint8))


def _stripes(path, size=64, lo=0.05, hi=0.5):
    """A grey roughness map: stripes of low and high roughness, plus a gradient (PNG, read raw)."""
    u = np.linspace(0, 1, size)
    grey = (
        lo
        + (hi - lo)
        * (0.5 + 0.5 * np.sign(np.sin(8 * math.pi * u)))[None, :]
        * np.linspace(0.3, 1, size)[:, None]
    )
    return _bitmap(path, (np.clip(grey, 0, 1) * 255).astype(np.uint8)[..., None])


def _sky(path, w=64, h=32, sun=(0.5, 0.25), sun_value=(40.0, 36.0, 30.0)):
    """A lat-long EXR: a blue-to-white sky, a darker ground and a small warm sun (a few pixels)."""
    v = (np.arange(h) + 0.5) / h
    u = (np.arange(w) + 0.5) / w
    vv, uu = np.meshgrid(v, u, indexing="ij")
    sky = np.stack([0.3 + 0.7 * vv, 0.45 + 0.5 * vv, 0.9 + 0.1 * vv], -1)
    ground = np.array([0.25, 0.2, 0.15])
    img = np.where((vv > 0.5)[..., None], ground, sky)
    d2 = ((uu - sun[0]) * w) ** 2 + ((vv - sun[1]) * h) ** 2
    img = np.where((d2 < 2.5)[..., None], np.array(sun_value), img)
    return _bitmap(path, img.astype(np.float32))


def _ply(path, vertices, faces, uv=None, vertex_colors=None, face_colors=None) -> str:
    """An ASCII PLY without normals (Mitsuba computes vertex normals on load)."""
    lines = ["ply", "format ascii 1.0", f"element vertex {len(vertices)}",
             "property float x", "property float y", "property float z"]
    if uv is not None:
        lines += ["property float u", "property float v"]
    if vertex_colors is not None:
        lines += ["property float r", "property float g", "property float b"]
    lines += [f"element face {len(faces)}", "property list uchar int vertex_indices"]
    if face_colors is not None:
        lines += ["property float r", "property float g", "property float b"]
    lines.append("end_header")
    for k, p in enumerate(vertices):
        row = list(p) + (list(uv[k]) if uv is not None else []) + \
            (list(vertex_colors[k]) if vertex_colors is not None else [])
        lines.append(" ".join(f"{x:.6f}" for x in row))
    for k, f in enumerate(faces):
        row = f"{len(f)} " + " ".join(str(int(i)) for i in f)
        if face_colors is not None:
            row += " " + " ".join(f"{x:.6f}" for x in face_colors[k])
        lines.append(row)
    path.write_text("\n".join(lines) + "\n")
    return path.name


def _hill(n=10):
    """A bumpy height field over [-1, 1]^2 (y up), with texture coordinates: smooth shading needs
    normals."""
    x = np.linspace(-1, 1, n)
    zz, xx = np.meshgrid(x, x, indexing="ij")
    yy = 0.6 * np.exp(-2.5 * (xx ** 2 + zz ** 2)) + 0.08 * np.sin(5 * xx) * np.cos(4 * zz)
    verts = np.stack([xx, yy, zz], -1).reshape(-1, 3)
    uv = np.stack([(xx + 1) / 2, (zz + 1) / 2], -1).reshape(-1, 2)
    faces = []
    for i in range(n - 1):
        for j in range(n - 1):
            a, b, c, d = i * n + j, i * n + j + 1, (i + 1) * n + j, (i + 1) * n + j + 1
            faces += [(a, c, b), (b, c, d)]
    return verts, np.array(faces), uv


# ---------------------------------------------------------------------------------------------- XML
# pieces

def _integrator(name: str) -> str:
    spec = REFERENCE_INTEGRATOR[name]
    props = "".join(
        f'<boolean name="{k}" value="{str(v).lower()}"/>'
        if isinstance(v, bool)
        else f'<integer name="{k}" value="{v}"/>'
        for k, v in spec.items()
        if k != "type"
    )
    if name in BY_DEFAULT:
        inner = (f'<default name="integrator" value="{spec["type"]}"/>'
                 f'<integrator type="$integrator">{props}</integrator>')
    else:
        inner = f'<integrator type="{spec["type"]}">{props}</integrator>'
    wrap = WRAPPER.get(name)
    if wrap == "moment":
        return f'<integrator type="moment">{inner}</integrator>'
    if wrap == "aov":
        return (
            f'<integrator type="aov"><string name="aovs" '
            f'value="dd.y:depth,nn:sh_normal"/>{inner}</integrator>'
        )
    return inner


def _sensor(kind="perspective", origin="0, 1.6, 4.5", target="0, 0.5, 0", extra="", scale=""):
    return f"""
    <sensor type="{kind}">
        {extra}
        <transform name="to_world">{scale}<lookat origin="{origin}" target="{target}" up="0, 1, \
0"/></transform>
        <sampler type="independent"><integer name="sample_count" value="$spp"/></sampler>
        <film type="hdrfilm">
            <integer name="width" value="{RES}"/><integer name="height" value="{RES}"/>
            <string name="pixel_format" value="rgb"/>
            <rfilter type="box"/>
        </film>
    </sensor>"""


def _floor(
    bsdf='<bsdf type="diffuse"><rgb name="reflectance" value="0.5, 0.5, 0.5"/></bsdf>', size=3.0
):
    return f"""
    <shape type="rectangle">
        <transform name="to_world"><scale value="{size}"/><rotate x="1" angle="-90"/></transform>
        {bsdf}
    </shape>"""


def _area_light(pos="0.6, 2.6, 0.8", scale=0.5, radiance="6, 5.5, 5"):
    return f"""
    <shape type="rectangle">
        <transform name="to_world"><scale value="{scale}"/><rotate x="1" angle="90"/><translate \
value="{pos}"/></transform>
        <bsdf type="diffuse"><rgb name="reflectance" value="0, 0, 0"/></bsdf>
        <emitter type="area"><rgb name="radiance" value="{radiance}"/></emitter>
    </shape>"""


def _scene(name: str, body: str) -> str:
    return f"""<?xml version="1.0" encoding="utf-8"?>
<!-- styletrace corpus scene '{name}': {FEATURES[name]} (tests/corpus/scenes.py) -->
<scene version="3.0.0">
    <default name="spp" value="16"/>
    {_integrator(name)}
    {body}
</scene>
"""


# ----------------------------------------------------------------------------------------------
# scenes

def _textured(folder: pathlib.Path) -> str:
    checker = _checker(folder / "checker.png")
    rough = _stripes(folder / "roughness.png")
    verts, faces, uv = _hill()
    hill = _ply(folder / "hill.ply", verts * np.array([0.8, 1.0, 0.8]), faces, uv=uv)
    return _sensor() + _floor(f"""<bsdf type="diffuse">
            <texture name="reflectance" type="bitmap"><string name="filename" \
value="{checker}"/></texture>
        </bsdf>""") + f"""
    <shape type="sphere">
        <point name="center" x="-1.0" y="0.55" z="0.3"/><float name="radius" value="0.55"/>
        <bsdf type="roughconductor">
            <string name="material" value="Au"/>
            <texture name="alpha" type="bitmap"><boolean name="raw" value="true"/>
                <string name="filename" value="{rough}"/></texture>
        </bsdf>
    </shape>
    <shape type="ply">
        <string name="filename" value="{hill}"/>
        <transform name="to_world"><translate x="0.7" y="0.0" z="0.2"/></transform>
        <bsdf type="principled">
            <texture name="base_color" type="bitmap"><string name="filename" \
value="{checker}"/></texture>
            <texture name="roughness" type="bitmap"><boolean name="raw" value="true"/>
                <string name="filename" value="{rough}"/></texture>
            <float name="metallic" value="0.2"/>
        </bsdf>
    </shape>""" + _area_light() + """
    <emitter type="point">
        <point name="position" x="-1.5" y="2.0" z="2.0"/><rgb name="intensity" value="4, 3.5, 3"/>
    </emitter>"""


def _envmap(folder):
    sky = _sky(folder / "sky.exr")
    i, j = np.meshgrid(np.arange(32), np.arange(32), indexing="ij")
    weight = _bitmap(
        folder / "weight.png",
        ((((i // 8 + j // 8) % 2) * 0.8 + 0.1) * 255).astype(np.uint8)[..., None],
    )
    return _sensor(origin="0, 1.8, 5") + _floor() + f"""
    <emitter type="envmap"><string name="filename" value="{sky}"/><float name="scale" \
value="1.0"/></emitter>
    <shape type="sphere">
        <point name="center" x="-1.2" y="0.5" z="0"/><float name="radius" value="0.5"/>
        <bsdf type="roughdielectric"><float name="alpha" value="0.15"/><float name="int_ior" \
value="1.5"/></bsdf>
    </shape>
    <shape type="sphere">
        <point name="center" x="0" y="0.5" z="-0.6"/><float name="radius" value="0.5"/>
        <bsdf type="roughplastic"><rgb name="diffuse_reflectance" value="0.7, 0.2, 0.1"/>
            <float name="alpha" value="0.2"/></bsdf>
    </shape>
    <shape type="sphere">
        <point name="center" x="1.2" y="0.5" z="0"/><float name="radius" value="0.5"/>
        <bsdf type="blendbsdf">
            <texture name="weight" type="bitmap"><boolean name="raw" value="true"/>
                <string name="filename" value="{weight}"/></texture>
            <bsdf type="diffuse"><rgb name="reflectance" value="0.2, 0.6, 0.2"/></bsdf>
            <bsdf type="roughconductor"><float name="alpha" value="0.1"/></bsdf>
        </bsdf>
    </shape>
    <shape type="rectangle">
        <transform name="to_world"><scale x="0.45" y="0.35"/><rotate y="1" angle="20"/><translate \
value="-0.4, 0.45, 1.3"/></transform>
        <bsdf type="thindielectric"><float name="int_ior" value="1.5"/></bsdf>
    </shape>
    <shape type="rectangle">
        <transform name="to_world"><scale x="0.4" y="0.35"/><rotate y="1" angle="-70"/><translate \
value="0.6, 0.4, 1.0"/></transform>
        <bsdf type="twosided">
            <bsdf type="diffuse"><rgb name="reflectance" value="0.8, 0.8, 0.1"/></bsdf>
            <bsdf type="diffuse"><rgb name="reflectance" value="0.1, 0.2, 0.8"/></bsdf>
        </bsdf>
    </shape>"""


def _normal_bump(folder):
    n = 64
    u = np.linspace(0, 4 * math.pi, n)
    # tangent-space normals of a corrugated surface, encoded n * 0.5 + 0.5 (read raw)
    nx = 0.6 * np.sin(u)[None, :].repeat(n, 0)
    ny = 0.3 * np.cos(u)[:, None].repeat(n, 1)
    nz = np.ones((n, n))
    norm = np.sqrt(nx ** 2 + ny ** 2 + nz ** 2)
    nmap = _bitmap(
        folder / "normals.exr",
        (np.stack([nx, ny, nz], -1) / norm[..., None] * 0.5 + 0.5).astype(np.float32),
    )
    i, j = np.meshgrid(np.arange(n), np.arange(n), indexing="ij")
    height = 0.5 + 0.5 * np.sin(i / 3.0) * np.sin(j / 3.0)
    bump = _bitmap(folder / "bumps.png", (height * 255).astype(np.uint8)[..., None])
    return _sensor() + _floor(f"""<bsdf type="normalmap">
            <texture name="normalmap" type="bitmap"><boolean name="raw" value="true"/>
                <string name="filename" value="{nmap}"/></texture>
            <bsdf type="roughplastic"><rgb name="diffuse_reflectance" value="0.6, 0.5, 0.4"/>
                <float name="alpha" value="0.25"/></bsdf>
        </bsdf>""") + f"""
    <shape type="sphere">
        <point name="center" x="0" y="0.7" z="0"/><float name="radius" value="0.7"/>
        <bsdf type="bumpmap">
            <texture name="bumpmap" type="bitmap"><boolean name="raw" value="true"/>
                <string name="filename" value="{bump}"/></texture>
            <float name="scale" value="0.6"/>
            <bsdf type="diffuse"><rgb name="reflectance" value="0.3, 0.5, 0.7"/></bsdf>
        </bsdf>
    </shape>
    <emitter type="spot">
        <transform name="to_world"><lookat origin="1.5, 3.0, 1.5" target="0, 0.3, 0" up="0, 1, \
0"/></transform>
        <rgb name="intensity" value="20, 18, 15"/><float name="cutoff_angle" value="25"/><float \
name="beam_width" value="18"/>
    </emitter>
    <emitter type="directional">
        <vector name="direction" x="0.5" y="-1" z="-0.4"/><rgb name="irradiance" value="0.6, 0.7, \
0.9"/>
    </emitter>"""


def _instances(folder):
    i, j = np.meshgrid(np.arange(32), np.arange(32), indexing="ij")
    slide = np.stack([(i / 31.0), (j / 31.0), 0.5 + 0.5 * ((i // 8 + j // 8) % 2)], -1)
    slide_name = _bitmap(folder / "slide.png", (slide * 255).astype(np.uint8))
    placements = "".join(
        f"""
    <shape type="instance"><ref id="{group}"/>
        <transform name="to_world"><rotate y="1" angle="{angle}"/><translate \
value="{pos}"/></transform>
    </shape>"""
        for group, angle, pos in [
            ("plain", 0, "-1.1, 0, -0.4"),
            ("plain", 35, "1.0, 0, 0.5"),
            ("styled_group", 10, "0.1, 0, -0.9"),
            ("styled_group", -40, "-0.5, 0, 1.0"),
        ]
    )
    scale = '<scale x="2.2" y="2.2" z="1"/>'  # the orthographic view covers 4.4 x 4.4 scene units
    return _sensor(
        "orthographic", origin="2.5, 4.0, 5.0", target="0, 0.3, 0", scale=scale
    ) + _floor() + f"""
    <shape type="shapegroup" id="plain">
        <shape type="cube">
            <transform name="to_world"><scale value="0.3"/><translate y="0.3"/></transform>
            <bsdf type="diffuse"><rgb name="reflectance" value="0.7, 0.3, 0.2"/></bsdf>
        </shape>
        <shape type="sphere">
            <point name="center" x="0" y="0.85" z="0"/><float name="radius" value="0.25"/>
            <bsdf type="roughplastic"><rgb name="diffuse_reflectance" value="0.2, 0.4, 0.7"/></bsdf>
        </shape>
    </shape>
    <shape type="shapegroup" id="styled_group">
        <shape type="cylinder">
            <point name="p0" x="0" y="0" z="0"/><point name="p1" x="0" y="0.7" z="0"/><float \
name="radius" value="0.3"/>
            <bsdf type="styled">
                <string name="style" value="identity"/><integer name="inner_samples" value="2"/>
                <bsdf type="diffuse"><rgb name="reflectance" value="0.3, 0.7, 0.3"/></bsdf>
            </bsdf>
        </shape>
    </shape>{placements}
    <emitter type="projector">
        <transform name="to_world"><lookat origin="-2.0, 3.5, 2.0" target="0, 0.3, 0" up="0, 1, \
0"/></transform>
        <texture name="irradiance" type="bitmap"><string name="filename" \
value="{slide_name}"/></texture>
        <float name="fov" value="50"/><float name="scale" value="8"/>
    </emitter>
    <emitter type="constant"><rgb name="radiance" value="0.15, 0.15, 0.2"/></emitter>"""


def _colours(folder):
    verts, faces, _ = _hill(8)
    verts = verts * np.array([0.9, 1.1, 0.9])
    vcol = np.clip(
        np.stack([0.5 + 0.5 * verts[:, 0], 0.3 + verts[:, 1], 0.5 - 0.5 * verts[:, 2]], -1),
        0.02,
        0.98,
    )
    rng = np.random.default_rng(18)
    fcol = rng.uniform(0.1, 0.9, size=(len(faces), 3))
    a = _ply(folder / "vertex_colours.ply", verts, faces, vertex_colors=vcol)
    b = _ply(folder / "face_colours.ply", verts, faces, face_colors=fcol)
    lens = ('<float name="fov" value="40"/><float name="aperture_radius" value="0.08"/>'
            '<float name="focus_distance" value="4.6"/>')
    return _sensor("thinlens", extra=lens) + _floor() + f"""
    <shape type="ply">
        <string name="filename" value="{a}"/>
        <transform name="to_world"><translate x="-1.0" z="0.0"/></transform>
        <bsdf type="diffuse"><texture name="reflectance" type="mesh_attribute"><string name="name" \
value="vertex_color"/></texture></bsdf>
    </shape>
    <shape type="ply">
        <string name="filename" value="{b}"/>
        <transform name="to_world"><translate x="1.0" z="-0.8"/></transform>
        <bsdf type="diffuse"><texture name="reflectance" type="mesh_attribute"><string name="name" \
value="face_color"/></texture></bsdf>
    </shape>""" + _area_light(scale=0.7) + """
    <emitter type="constant"><rgb name="radiance" value="0.2, 0.2, 0.2"/></emitter>"""


def _direct(folder):
    checker = _checker(folder / "checker.png", n=4)
    return _sensor() + _floor(f"""<bsdf type="diffuse">
            <texture name="reflectance" type="bitmap"><string name="filename" \
value="{checker}"/></texture>
        </bsdf>""") + """
    <shape type="sphere">
        <point name="center" x="0" y="0.6" z="0"/><float name="radius" value="0.6"/>
        <bsdf type="roughplastic"><rgb name="diffuse_reflectance" value="0.5, 0.3, 0.6"/><float \
name="alpha" value="0.15"/></bsdf>
    </shape>""" + _area_light(pos="-0.5, 2.0, 1.2", scale=0.6) + """
    <emitter type="constant"><rgb name="radiance" value="0.4, 0.45, 0.5"/></emitter>"""


def _direct_default(folder):
    # seen from below the sphere's centre: its underside has no direct light (black in `direct`, lit
    # by the plane in any deeper integrator), and neither has its shadow on the plane
    return _sensor(origin="0, 0.8, 4.2", target="0, 0.9, 0") + _floor() + """
    <shape type="sphere">
        <point name="center" x="0" y="1.2" z="0"/><float name="radius" value="0.55"/>
        <bsdf type="diffuse"><rgb name="reflectance" value="0.7, 0.6, 0.5"/></bsdf>
    </shape>
    <emitter type="directional">
        <vector name="direction" x="0.35" y="-1" z="-0.25"/><rgb name="irradiance" value="2, 2, 2"/>
    </emitter>"""


def _ptracer(folder):
    # all diffuse: a light tracer cannot connect specular vertices to the camera
    return _sensor() + _floor() + """
    <shape type="cube">
        <transform name="to_world"><scale value="0.45"/><rotate y="1" angle="30"/><translate \
value="-0.7, 0.45, 0"/></transform>
        <bsdf type="diffuse"><rgb name="reflectance" value="0.8, 0.4, 0.2"/></bsdf>
    </shape>
    <shape type="sphere">
        <point name="center" x="0.8" y="0.5" z="0.3"/><float name="radius" value="0.5"/>
        <bsdf type="diffuse"><rgb name="reflectance" value="0.2, 0.5, 0.8"/></bsdf>
    </shape>
    <shape type="rectangle">
        <transform name="to_world"><scale value="3"/><translate value="0, 3, -2"/></transform>
        <bsdf type="diffuse"><rgb name="reflectance" value="0.6, 0.6, 0.6"/></bsdf>
    </shape>""" + _area_light(pos="0, 2.4, 0.5", scale=0.6, radiance="8, 7.5, 7")


def _medium_light(folder):
    # a fog-filled box (null boundary); inside it a small spherical area light and a diffuse sphere,
    # both with the fog as their exterior medium; the camera sits outside
    return _sensor(origin="0, 1.4, 4.8", target="0, 0.7, 0") + _floor() + """
    <medium type="homogeneous" id="fog">
        <rgb name="sigma_t" value="0.6, 0.8, 1.0"/><rgb name="albedo" value="0.9, 0.8, \
0.7"/><float name="scale" value="0.8"/>
    </medium>
    <shape type="cube">
        <transform name="to_world"><scale x="1.4" y="0.9" z="1.0"/><translate y="0.95"/></transform>
        <bsdf type="null"/>
        <ref name="interior" id="fog"/>
    </shape>
    <shape type="sphere">
        <point name="center" x="-0.6" y="1.3" z="0.2"/><float name="radius" value="0.18"/>
        <ref name="exterior" id="fog"/>
        <emitter type="area"><rgb name="radiance" value="12, 11, 9"/></emitter>
    </shape>
    <shape type="sphere">
        <point name="center" x="0.5" y="0.6" z="0"/><float name="radius" value="0.45"/>
        <ref name="exterior" id="fog"/>
        <bsdf type="diffuse"><rgb name="reflectance" value="0.7, 0.5, 0.3"/></bsdf>
    </shape>""" + _area_light(pos="1.2, 2.6, 1.5", scale=0.3, radiance="4, 4, 4")


def _smoke_env(folder):
    import mitsuba as mi
    sky = _sky(folder / "sky.exr", sun=(0.3, 0.2), sun_value=(20.0, 18.0, 15.0))
    x = np.linspace(-1, 1, 8)
    zz, yy, xx = np.meshgrid(x, x, x, indexing="ij")
    density = (np.clip(1.3 - (xx ** 2 + yy ** 2 + zz ** 2), 0.0, None) * 3.0).astype(np.float32)
    albedo = np.stack(
        [0.5 + 0.4 * (xx + 1) / 2, 0.8 * np.ones_like(xx), 0.9 - 0.4 * (yy + 1) / 2], -1
    )
    mi.VolumeGrid(density[..., None]).write(str(folder / "density.vol"))
    mi.VolumeGrid(albedo.astype(np.float32)).write(str(folder / "albedo.vol"))
    box = '<scale value="0.8"/><translate y="0.85"/>'
    grid_to_world = '<translate value="-1, -1, -1"/><scale value="2"/>' + box
    return _sensor(origin="0, 1.5, 4.5", target="0, 0.7, 0") + _floor() + f"""
    <emitter type="envmap"><string name="filename" value="{sky}"/></emitter>
    <medium type="heterogeneous" id="smoke">
        <volume name="sigma_t" type="gridvolume"><string name="filename" value="density.vol"/>
            <transform name="to_world">{grid_to_world}</transform></volume>
        <volume name="albedo" type="gridvolume"><string name="filename" value="albedo.vol"/>
            <transform name="to_world">{grid_to_world}</transform></volume>
        <float name="scale" value="4.0"/>
        <phase type="hg"><float name="g" value="0.3"/></phase>
    </medium>
    <shape type="cube">
        <transform name="to_world">{box}</transform>
        <bsdf type="null"/>
        <ref name="interior" id="smoke"/>
    </shape>"""


_BUILDERS = {
    "textured": _textured,
    "envmap": _envmap,
    "normal_bump": _normal_bump,
    "instances": _instances,
    "colours": _colours,
    "direct": _direct,
    "direct_default": _direct_default,
    "ptracer": _ptracer,
    "medium_light": _medium_light,
    "smoke_env": _smoke_env,
}
assert list(_BUILDERS) == SCENES


def write_scene(name: str, folder: pathlib.Path) -> pathlib.Path:
    """Write scene `name` (its XML and assets) into `folder`; return the XML's path.

    Needs Mitsuba with a variant set (`styletrace.init()`) for the bitmap and volume writers."""
    if name not in _BUILDERS:
        raise KeyError(f"unknown corpus scene {name!r}: expected one of {', '.join(SCENES)}")
    folder = pathlib.Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    body = _BUILDERS[name](folder)
    path = folder / f"{name}.xml"
    path.write_text(_scene(name, body))
    return path
