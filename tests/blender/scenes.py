"""Scenes built with bpy for the add-on's tests, and the two renderers run on them: Cycles (the
reference) and styletrace's engine (F12). Images are read back from EXR files written by Blender
itself (single-part EXR, so every pass is a channel Mitsuba's reader sees)."""
from __future__ import annotations

import math
import os

import bpy
import numpy as np

CACHE = os.path.join(os.path.dirname(__file__), ".cache")


def reset(size: int = 64):
    bpy.ops.wm.read_factory_settings(use_empty=True)
    s = bpy.context.scene
    s.render.resolution_x = s.render.resolution_y = size
    s.render.resolution_percentage = 100
    s.render.threads_mode = "FIXED"
    s.render.threads = 2
    s.view_settings.view_transform = "Standard"
    s.render.image_settings.media_type = "MULTI_LAYER_IMAGE"  # every render pass is written
    s.render.image_settings.file_format = "OPEN_EXR_MULTILAYER"
    s.render.image_settings.color_depth = "32"
    s.render.image_settings.use_exr_interleave = True  # one part: every pass is a channel of it
    w = bpy.data.worlds.new("world")
    s.world = w
    if w.node_tree is None:
        w.use_nodes = True
    w.node_tree.nodes["Background"].inputs["Strength"].default_value = 0.0
    return s


def material(name, kind="ShaderNodeBsdfDiffuse", **inputs):
    mat = bpy.data.materials.new(name)
    if mat.node_tree is None:  # Blender < 5 (5.0 makes every material a node tree)
        mat.use_nodes = True
    nt = mat.node_tree
    for n in list(nt.nodes):
        if n.bl_idname != "ShaderNodeOutputMaterial":
            nt.nodes.remove(n)
    node = nt.nodes.new(kind)
    for key, value in inputs.items():
        sock = node.inputs[key]
        sock.default_value = (
            (*value, 1.0) if isinstance(value, tuple) and len(value) == 3 else value
        )
    nt.links.new(node.outputs[0], nt.nodes["Material Output"].inputs["Surface"])
    return mat, node


def add(obj, mat=None):
    if mat is not None:
        obj.data.materials.append(mat)
    return obj


def plane(size, location=(0, 0, 0), rotation=(0, 0, 0), mat=None):
    bpy.ops.mesh.primitive_plane_add(size=size, location=location, rotation=rotation)
    return add(bpy.context.object, mat)


def cube(size, location, mat=None):
    bpy.ops.mesh.primitive_cube_add(size=size, location=location)
    return add(bpy.context.object, mat)


def sphere(radius, location, mat=None, smooth=True):
    bpy.ops.mesh.primitive_uv_sphere_add(
        radius=radius, location=location, segments=48, ring_count=24
    )
    obj = bpy.context.object
    if smooth:
        bpy.ops.object.shade_smooth()
    return add(obj, mat)


def light(kind, location, rotation=(0, 0, 0), **values):
    data = bpy.data.lights.new(kind.lower(), kind)
    for k, v in values.items():
        setattr(data, k, v)
    obj = bpy.data.objects.new(data.name, data)
    bpy.context.scene.collection.objects.link(obj)
    obj.location, obj.rotation_euler = location, rotation
    return obj


def camera(location, rotation, lens=35.0, **values):
    data = bpy.data.cameras.new("camera")
    data.lens = lens
    for k, v in values.items():
        setattr(data, k, v)
    obj = bpy.data.objects.new("camera", data)
    bpy.context.scene.collection.objects.link(obj)
    obj.location, obj.rotation_euler = location, rotation
    bpy.context.scene.camera = obj
    return obj


def look(location, target):
    """Euler rotation of a Blender camera at `location` looking at `target` (up: +Z)."""
    from mathutils import Vector
    d = Vector(target) - Vector(location)
    return d.to_track_quat("-Z", "Y").to_euler()


# ---- the comparison scenes -----------------------------------------------------------------------

def room(size: int = 64):
    """A diffuse room open to the sky: floor and three walls, an area light under the open top
    and a sun."""
    s = reset(size)
    white, _ = material("white", Color=(0.8, 0.8, 0.8))
    red, _ = material("red", Color=(0.8, 0.15, 0.1))
    green, _ = material(
        "green",
        "ShaderNodeBsdfPrincipled",
        **{"Base Color": (0.15, 0.7, 0.2), "Specular IOR Level": 0.0, "Roughness": 1.0},
    )
    plane(4, (0, 0, 0), mat=white)
    plane(4, (0, 2, 2), (math.pi / 2, 0, 0), mat=white)
    plane(4, (-2, 0, 2), (0, math.pi / 2, 0), mat=red)
    plane(4, (2, 0, 2), (0, math.pi / 2, 0), mat=green)
    cube(1.0, (0.5, 0.6, 0.5), mat=white)
    # out of view: Blender 5 hides lights from the camera
    light("AREA", (0, -0.5, 4.5), energy=150.0, size=1.0)
    # the sun shines towards the camera: the area light's shadow (Cycles' lights cast none;
    # styletrace's do, docs/blender.md) falls outside the room
    light("SUN", (0, 0, 10), (math.radians(35), 0, math.radians(210)), energy=2.0, angle=0.0)
    camera((0, -7, 2.0), look((0, -7, 2.0), (0, 0, 1.4)), lens=40)
    return s


def texel_material(name: str, seed: int, grey: bool = False, size: int = 16):
    """A diffuse material of `size` x `size` random texels in [0.1, 0.9] (grey: the same in every
    channel), drawn without interpolation (Closest), so that a shift of the view shows."""
    img = bpy.data.images.new(name, size, size)
    px = np.ones((size, size, 4), np.float32)
    px[..., :3] = np.random.default_rng(seed).uniform(0.1, 0.9, (size, size, 1 if grey else 3))
    img.pixels.foreach_set(px.reshape(-1))
    img.pack()
    mat, node = material(name)
    tex = mat.node_tree.nodes.new("ShaderNodeTexImage")
    tex.image, tex.interpolation = img, "Closest"
    mat.node_tree.links.new(tex.outputs["Color"], node.inputs["Color"])
    return mat


def checker_image(name="checker", size=32):
    """An 8-bit sRGB texture, asymmetric in v (blue rising, red-green falling) and periodic in u
    (red and green alternating), so that it tiles without a seam. Smooth: Cycles interpolates
    8-bit sRGB texels before decoding them, styletrace after (docs/blender.md), which differs by
    a few percent across hard texel edges."""
    img = bpy.data.images.new(name, size, size, alpha=True)
    u = (np.arange(size) + 0.5) / size
    px = np.ones((size, size, 4), np.float32)
    px[..., 0] = 0.5 + 0.5 * np.cos(2 * np.pi * u[None, :])
    px[..., 1] = 0.5 - 0.5 * np.cos(2 * np.pi * u[None, :])
    v = (np.arange(size) + 0.5) / size  # rows are bottom first: v = 1 is the top
    px[..., 2] = 0.1 + 0.8 * v[:, None] ** 2
    px[..., :2] *= (1.0 - 0.7 * v[:, None] ** 2)[..., None]
    img.pixels.foreach_set(px.reshape(-1))
    img.pack()
    return img


def sky_image(name="sky", w=64, h=32):
    """A float equirectangular map: a blue-white gradient and a warm bright patch off to one
    side."""
    img = bpy.data.images.new(name, w, h, alpha=True, float_buffer=True)
    y = (np.arange(h) + 0.5) / h  # bottom row first: y = 0 looks down
    px = np.ones((h, w, 4), np.float32)
    px[..., 0] = 0.2 + 0.6 * y[:, None]
    px[..., 1] = 0.3 + 0.5 * y[:, None]
    px[..., 2] = 0.9
    px[int(h * 0.6):int(h * 0.8), int(w * 0.1):int(w * 0.25), :3] = (6.0, 4.0, 1.5)
    img.pixels.foreach_set(px.reshape(-1))
    img.pack()
    return img


def world_texture(strength=1.0):
    w = bpy.context.scene.world
    nt = w.node_tree
    env = nt.nodes.new("ShaderNodeTexEnvironment")
    env.image = sky_image()
    bg = nt.nodes["Background"]
    bg.inputs["Strength"].default_value = strength
    nt.links.new(env.outputs["Color"], bg.inputs["Color"])


def textured_plane(size: int = 64):
    """A plane with an image-textured Principled BSDF under an HDR world, seen at an angle with
    sky in view."""
    s = reset(size)
    mat, node = material(
        "tex", "ShaderNodeBsdfPrincipled", **{"Specular IOR Level": 0.0, "Roughness": 1.0}
    )
    tex = mat.node_tree.nodes.new("ShaderNodeTexImage")
    tex.image = checker_image()
    mat.node_tree.links.new(tex.outputs["Color"], node.inputs["Base Color"])
    plane(4, (0, 0, 0), (0, 0, math.radians(20)), mat=mat)
    world_texture(1.0)
    camera((0, -5.5, 2.5), look((0, -5.5, 2.5), (0, 0, 0.8)), lens=30)
    return s


def sphere_scene(kind: str, size: int = 64):
    """A glossy metal ('glossy') or glass ('glass') sphere on a diffuse floor, under the HDR
    world and a point light."""
    s = reset(size)
    floor, _ = material("floor", Color=(0.6, 0.6, 0.6))
    plane(20, (0, 0, 0), mat=floor)
    if kind == "glossy":
        mat, _ = material("metal", "ShaderNodeBsdfGlossy", Color=(0.95, 0.64, 0.54), Roughness=0.35)
    else:
        mat, _ = material(
            "glass", "ShaderNodeBsdfGlass", Color=(1.0, 1.0, 1.0), Roughness=0.0, IOR=1.5
        )
    sphere(1.0, (0, 0, 1.0), mat=mat)
    world_texture(0.8)
    light("POINT", (2.5, -2.0, 4.0), energy=800.0, shadow_soft_size=0.0)
    camera((0, -5.0, 2.2), look((0, -5.0, 2.2), (0, 0, 0.9)), lens=35)
    return s


def instanced(size: int = 64):
    """A collection (cube and sphere) instanced three times by empties, on a floor under an area
    light and sun."""
    s = reset(size)
    white, _ = material("white", Color=(0.8, 0.8, 0.8))
    blue, _ = material("blue", Color=(0.2, 0.3, 0.8))
    plane(12, (0, 0, 0), mat=white)
    coll = bpy.data.collections.new("thing")
    s.collection.children.link(coll)
    c = cube(0.8, (0, 0, 0.4), mat=blue)
    sp = sphere(0.35, (0, 0, 1.15), mat=white)
    for obj in (c, sp):
        for other in list(obj.users_collection):
            other.objects.unlink(obj)
        coll.objects.link(obj)
    s.view_layers[0].layer_collection.children["thing"].exclude = True  # only the instances render
    for k, (x, y, rz) in enumerate(((-1.6, 0.5, 0.3), (0.0, 0.0, 0.9), (1.6, 0.8, -0.5))):
        e = bpy.data.objects.new(f"inst{k}", None)
        e.instance_type = "COLLECTION"
        e.instance_collection = coll
        e.location, e.rotation_euler = (x, y, 0), (0, 0, rz)
        e.scale = (1.0, 1.0, 1.0 + 0.25 * k)
        s.collection.objects.link(e)
    light("AREA", (0, -3, 6), (math.radians(-25), 0, 0), energy=400.0, size=2.0)  # out of view
    # the sun shines towards the camera, so the area light's shadow falls behind it (see `room`)
    light("SUN", (0, 0, 10), (math.radians(40), 0, math.radians(200)), energy=1.0, angle=0.0)
    camera((0, -6.5, 3.5), look((0, -6.5, 3.5), (0, 0.3, 0.5)), lens=32)
    return s


def interior(size: int = 64):
    """A room lit through a window: a sun and a blue sky outside, a small area lamp on the ceiling,
    a glossy floor, a mirror, Principled materials. The sun falls through the window onto the
    floor; the rest of the room is lit by what bounces off that patch, the sky seen through the
    window and the lamp (the hard light of real interiors)."""
    s = reset(size)

    def principled(name, colour, roughness=0.9, specular=0.5, metallic=0.0):
        return material(name, "ShaderNodeBsdfPrincipled", **{
            "Base Color": colour, "Roughness": roughness, "Specular IOR Level": specular,
            "Metallic": metallic})[0]

    wall = principled("wall", (0.75, 0.72, 0.65))
    floor = principled("floor", (0.45, 0.28, 0.15), roughness=0.25)
    ceiling = principled("ceiling", (0.8, 0.8, 0.8))
    sofa = principled("sofa", (0.15, 0.3, 0.6))
    table = principled("table", (0.7, 0.5, 0.3), roughness=0.5)
    vase = principled("vase", (0.8, 0.2, 0.1), roughness=0.3)
    mirror = principled("mirror", (0.9, 0.9, 0.9), roughness=0.02, metallic=1.0)
    # a 6 x 6 x 3 room; the wall at x = 3 has a 2 x 1.4 window, its centre at y = 0.5, z = 1.6
    plane(6, (0, 0, 0), mat=floor)
    plane(6, (0, 0, 3), (math.pi, 0, 0), mat=ceiling)
    plane(6, (0, 3, 1.5), (math.pi / 2, 0, 0), mat=wall)
    plane(6, (0, -3, 1.5), (-math.pi / 2, 0, 0), mat=wall)
    plane(6, (-3, 0, 1.5), (0, math.pi / 2, 0), mat=wall)
    for (y0, y1, z0, z1) in ((-3, -0.5, 0, 3), (1.5, 3, 0, 3), (-0.5, 1.5, 0, 0.9),
                             (-0.5, 1.5, 2.3, 3)):
        piece = cube(1.0, (3.05, (y0 + y1) / 2, (z0 + z1) / 2), mat=wall)
        piece.scale = (0.1, y1 - y0, z1 - z0)
    cube(1.0, (-2.2, 1.0, 0.4), mat=sofa).scale = (1.2, 2.4, 0.8)
    cube(1.0, (0.3, 0.6, 0.35), mat=table).scale = (1.2, 0.8, 0.7)
    sphere(0.25, (0.3, 0.6, 0.95), mat=vase)
    m = plane(1.0, (-2.95, -1.2, 1.5), (0, math.pi / 2, 0), mat=mirror)
    m.scale = (1.8, 1.2, 1.0)  # the mirror on the back wall, facing the window
    world = s.world.node_tree.nodes["Background"]
    world.inputs["Color"].default_value = (0.35, 0.55, 1.0, 1.0)
    world.inputs["Strength"].default_value = 1.5
    light("SUN", (6, 0, 6), (0, math.radians(55), math.radians(-10)), energy=4.0,
          angle=math.radians(1.0))
    light("AREA", (-2.4, -2.4, 2.9), energy=40.0, size=0.25)  # above the camera, out of view
    camera((-2.6, -2.6, 1.7), look((-2.6, -2.6, 1.7), (2.0, 1.0, 1.0)), lens=22)
    return s


SCENES = {
    "room": room,
    "textured_plane": textured_plane,
    "glossy": lambda size=64: sphere_scene("glossy", size),
    "glass": lambda size=64: sphere_scene("glass", size),
    "instanced": instanced,
    "interior": interior,
}


# ---- rendering -----------------------------------------------------------------------------------

def read_exr(path: str) -> dict[str, np.ndarray]:
    """{pass name: H x W x C float32} of a single-part EXR Blender wrote."""
    import mitsuba as mi
    bmp = mi.Bitmap(path)
    arr = np.array(bmp, dtype=np.float32)
    names = [bmp.struct_()[i].name for i in range(arr.shape[-1])]
    out: dict[str, list] = {}
    for i, name in enumerate(names):
        parts = name.split(".")
        layer_pass = parts[-2] if len(parts) >= 2 else "Combined"
        out.setdefault(layer_pass, []).append((parts[-1], arr[..., i]))
    order = "RGBAXYZW"  # Vector is X, Y, Z, W
    return {
        k: np.stack([a for _, a in sorted(v, key=lambda t: order.find(t[0]))], axis=-1)
        for k, v in out.items()
    }


def f12(path: str) -> dict[str, np.ndarray]:
    """Render the current scene with its engine (bpy.ops.render.render, as F12) and read every
    pass back."""
    s = bpy.context.scene
    s.render.filepath = path
    bpy.ops.render.render(write_still=True)
    return read_exr(path)


def cycles(path: str, spp: int, seed: int = 0) -> np.ndarray:
    """The current scene rendered by Cycles on the CPU: no denoising, adaptive sampling, clamping
    or caustics filter, a one-pixel box filter (as styletrace's film); returns H x W x 3."""
    s = bpy.context.scene
    s.render.engine = "CYCLES"
    c = s.cycles
    c.device = "CPU"
    c.samples = spp
    c.seed = seed
    c.use_adaptive_sampling = False
    c.use_denoising = False
    c.sample_clamp_direct = c.sample_clamp_indirect = 0.0
    c.blur_glossy = 0.0
    c.max_bounces = c.diffuse_bounces = c.glossy_bounces = c.transmission_bounces = 64
    c.transparent_max_bounces = 64
    c.caustics_reflective = c.caustics_refractive = True
    c.pixel_filter_type = "BOX"
    c.filter_width = 1.0
    return f12(path)["Combined"][..., :3]


def cycles_reference(name: str, spp: int, builder=None) -> tuple[np.ndarray, np.ndarray]:
    """(mean image, its per-pixel variance) of scene `name` from two Cycles renders with
    different seeds, cached under tests/blender/.cache (ignored by git). The variance of the mean
    of two renders is estimated per pixel as ((a - b) / 2)^2; a block's variance is the mean of
    its pixels' over the block's pixel count."""
    os.makedirs(CACHE, exist_ok=True)
    cached = os.path.join(CACHE, f"{name}-{spp}-{bpy.app.version_string}.npz")
    if os.path.exists(cached):
        with np.load(cached) as f:
            return f["mean"], f["var"]
    (builder or SCENES[name])()
    files = [os.path.join(CACHE, f"{name}-{k}.exr") for k in "ab"]
    a, b = (cycles(f, spp, seed=seed) for f, seed in zip(files, (1, 2)))
    for f in files:
        os.remove(f)
    mean, var = (a + b) / 2, ((a - b) / 2) ** 2
    np.savez(cached, mean=mean, var=var)
    return mean, var


def styletrace(path: str, spp: int, seed: int = 0, pass_spp: int | None = None, **settings) -> dict:
    s = bpy.context.scene
    s.render.engine = "STYLETRACE"
    st = s.styletrace
    st.spp, st.seed = spp, seed
    st.pass_spp = pass_spp or spp
    for k, v in settings.items():
        setattr(st, k, v)
    return f12(path)


def blocks(img: np.ndarray, b: int = 8) -> np.ndarray:
    h, w = img.shape[:2]
    return (
        img[: h - h % b, : w - w % b]
        .reshape(h // b, b, w // b, b, *img.shape[2:])
        .mean(axis=(1, 3))
    )


#: relative allowance for deterministic differences: pixels that see an environment map directly
#: have no noise at all, and the renderers filter the map differently (0.1% seen on the textured
#: plane's sky)
ALLOWANCE = 0.005


def block_z(st_mean, st_var, cy_mean, cy_var, b: int = 8) -> np.ndarray:
    """Per-block z scores of the brightness (mean of RGB): difference of the block means over the
    standard error of that difference (the pixels' variances add; a block mean divides them by
    its b*b pixels), with `ALLOWANCE` of the block's brightness added in quadrature."""
    u = lambda a: a.mean(axis=-1)  # noqa: E731
    diff = blocks(u(st_mean), b) - blocks(u(cy_mean), b)
    # per-pixel variance of the brightness: the RGB channels are correlated, so the variance of
    # their mean is bounded by the mean of their standard deviations, squared
    sv = np.sqrt(np.maximum(st_var, 0)).mean(axis=-1) ** 2
    cv = np.sqrt(np.maximum(cy_var, 0)).mean(axis=-1) ** 2
    se = np.sqrt(
        (blocks(sv, b) + blocks(cv, b)) / (b * b) + (ALLOWANCE * blocks(u(cy_mean), b)) ** 2
    )
    return diff / np.maximum(se, 1e-12)
