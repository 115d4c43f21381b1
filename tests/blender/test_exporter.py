"""The depsgraph exporter on its own: modifiers applied, loop normals (smooth and flat), UVs, one
shape per material slot, the material mapping, and one warning per unsupported node."""
import bpy
import numpy as np
import scenes as S

from styletrace.blender import build, exporter


def shapes(desc):
    return [v for v in desc.values() if isinstance(v, dict) and v.get("type") == "blender_mesh"]


def export(warnings=None):
    return exporter.export(bpy.context.evaluated_depsgraph_get(), spp=4,
                           warn=(warnings.append if warnings is not None else print))


def test_modifiers_normals_uvs_and_slots():
    S.reset(16)
    S.camera((0, -5, 0), (np.pi / 2, 0, 0))
    flat = S.cube(1.0, (-1.5, 0, 0))
    smooth = S.sphere(0.5, (1.5, 0, 0), smooth=True)
    smooth.modifiers.new("sub", "SUBSURF").levels = 1
    a, _ = S.material("a")
    b, _ = S.material("b", Color=(0.1, 0.2, 0.3))
    flat.data.materials.append(a)
    flat.data.materials.append(b)
    flat.data.polygons[0].material_index = 1  # one face of the cube in the second slot
    desc = export()
    parts = {s["name"]: s["part"] for s in shapes(desc)}
    assert set(parts) == {"Cube.0", "Cube.1", "Sphere.0"}
    assert len(parts["Cube.1"].faces) == 2 and len(parts["Cube.0"].faces) == 10
    # flat cube: every triangle's corners carry its face normal, axis-aligned
    n = parts["Cube.0"].normals
    assert np.allclose(np.sort(np.abs(n), axis=1)[:, :2], 0, atol=1e-6)
    # the subdivided sphere has about 4x the faces of the original, smooth normals ~ radial
    assert len(parts["Sphere.0"].faces) >= 4 * 48 * 24 * 2 * 0.9
    p = parts["Sphere.0"].positions - np.array([1.5, 0, 0])
    cos = np.sum(p / np.linalg.norm(p, axis=1, keepdims=True) * parts["Sphere.0"].normals, axis=1)
    assert cos.min() > 0.95
    assert parts["Sphere.0"].uvs is not None and parts["Sphere.0"].uvs.shape[1] == 2
    # the description builds into a Mitsuba scene
    import styletrace
    scene = styletrace.frontends.api.load_scene(build.description_scene_dict(desc))
    assert len(scene.shapes()) == 3


def test_material_mapping_and_unsupported_nodes():
    S.reset(16)
    S.camera((0, -5, 0), (np.pi / 2, 0, 0))
    glass, _ = S.material("glass", "ShaderNodeBsdfGlass", IOR=1.33)
    metal, _ = S.material("metal", "ShaderNodeBsdfPrincipled", Metallic=1.0, Roughness=0.5)
    lamp, _ = S.material("lamp", "ShaderNodeEmission", Color=(1.0, 0.5, 0.25), Strength=4.0)
    leaf, node = S.material("leaf", "ShaderNodeBsdfPrincipled", Alpha=0.5)
    odd1, _ = S.material("odd1", "ShaderNodeBsdfToon")
    odd2, _ = S.material("odd2", "ShaderNodeBsdfToon")
    noise = leaf.node_tree.nodes.new("ShaderNodeTexNoise")
    leaf.node_tree.links.new(noise.outputs["Fac"], node.inputs["Roughness"])
    for k, mat in enumerate((glass, metal, lamp, leaf, odd1, odd2)):
        S.plane(0.5, (k - 2.5, 0, 0), (np.pi / 2, 0, 0), mat=mat)
    warnings = []
    desc = export(warnings)
    bsdfs = {s["name"]: s for s in shapes(desc)}
    assert bsdfs["Plane.0"]["bsdf"]["type"] == "roughdielectric" and np.isclose(
        bsdfs["Plane.0"]["bsdf"]["int_ior"], 1.33
    )
    assert bsdfs["Plane.001.0"]["bsdf"]["nested"]["type"] == "roughconductor"  # twosided(metal)
    assert np.isclose(bsdfs["Plane.001.0"]["bsdf"]["nested"]["alpha"], 0.25)  # roughness squared
    assert np.allclose(bsdfs["Plane.002.0"]["emitter"]["radiance"]["value"], (4.0, 2.0, 1.0))
    assert bsdfs["Plane.003.0"]["bsdf"]["type"] == "mask"
    # grey diffuse
    assert bsdfs["Plane.004.0"]["bsdf"]["nested"]["reflectance"]["value"] == (0.5, 0.5, 0.5)
    # one warning per unsupported node type, naming it and its materials
    assert len(warnings) == 2, warnings
    toon = next(w for w in warnings if "ShaderNodeBsdfToon" in w)
    assert "odd1" in toon and "odd2" in toon and "grey diffuse" in toon
    assert any("ShaderNodeTexNoise" in w and "leaf" in w for w in warnings)


def test_a_light_portal_is_left_out_with_a_note():
    """A Cycles portal emits nothing (it only steers Cycles' sampling of the world): it must not
    become a light; the area light beside it still does."""
    S.reset(16)
    S.camera((0, -5, 0), (np.pi / 2, 0, 0))
    window = S.light("AREA", (0, 0, 2), energy=100.0, size=1.0)
    window.data.cycles.is_portal = True
    S.light("AREA", (2, 0, 2), energy=10.0, size=0.3)
    warnings = []
    desc = export(warnings)
    emitting = [v for v in desc.values() if isinstance(v, dict) and "emitter" in v]
    assert len(emitting) == 1
    assert emitting[0]["to_world"][0][3] == 2.0  # the lamp at x = 2, not the window at x = 0
    assert [w for w in warnings if "light portal" in w and window.data.name in w]
