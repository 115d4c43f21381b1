"""The depsgraph exporter on its own: modifiers applied, loop normals (smooth and flat), UVs, one
shape per material slot, the material mapping, and one warning per unsupported node."""
import bpy
import numpy as np
import pytest
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


def test_a_light_portal_becomes_a_portal_emitter():
    """A Cycles portal emits nothing; it becomes the `portal` emitter over the light's rectangle,
    facing into the room along the light's -Z, and the area light beside it is still a light. A
    disk portal is sampled through its bounding square (with a note); one of zero size is left out
    (with a note), where loading it would refuse the scene."""
    S.reset(16)
    S.camera((0, -5, 0), (np.pi / 2, 0, 0))
    # a window in the wall y = 2, 1.5 wide and 0.8 tall, the room on its -y side: the light
    # turned to face -y (its -Z along -y)
    window = S.light("AREA", (0, 2, 1), (-np.pi / 2, 0, 0), shape="RECTANGLE", size=1.5,
                     size_y=0.8)
    window.data.cycles.is_portal = True
    round_one = S.light("AREA", (0, -3, 1), (np.pi / 2, 0, 0), shape="DISK", size=0.5)
    round_one.data.cycles.is_portal = True
    flat = S.light("AREA", (0, 0, 3), size=0.0)
    flat.data.cycles.is_portal = True
    S.light("AREA", (2, 0, 2), energy=10.0, size=0.3)
    warnings = []
    desc = export(warnings)
    emitting = [v for v in desc.values() if isinstance(v, dict) and "emitter" in v]
    assert len(emitting) == 1
    assert emitting[0]["to_world"][0][3] == 2.0  # the lamp at x = 2, not a portal
    portals = [v for v in desc.values() if isinstance(v, dict) and v.get("type") == "portal"]
    assert len(portals) == 2
    import styletrace
    from styletrace.kernel.portal import is_portal
    scene = styletrace.frontends.api.load_scene(build.description_scene_dict(desc))
    built = sorted((e for e in scene.emitters() if is_portal(e)), key=lambda e: e.center[1])
    disk, wall = built
    np.testing.assert_allclose(wall.center, [0, 2, 1], atol=1e-6)
    np.testing.assert_allclose(wall.normal, [0, -1, 0], atol=1e-6)  # into the room
    assert wall.area == pytest.approx(1.5 * 0.8, rel=1e-6)
    np.testing.assert_allclose(sorted(np.abs([wall.edge_x[0], wall.edge_y[2]])), [0.4, 0.75],
                               atol=1e-6)
    np.testing.assert_allclose(disk.normal, [0, 1, 0], atol=1e-6)
    assert disk.area == pytest.approx(0.5 * 0.5, rel=1e-6)
    assert [w for w in warnings if "light portal" in w and f"'{round_one.data.name}'" in w
            and "bounding rectangle" in w]
    assert [w for w in warnings if f"'{flat.data.name}'" in w and "zero size" in w]
    assert not [w for w in warnings if f"'{window.data.name}'" in w]


def test_instanced_objects_with_dots_in_their_names_load():
    """Blender names copies 'Cube.001'; Mitsuba refuses a '.' in an id, so the shape group's id
    keeps letters, digits and underscores and a digest of the name (two names that differ only
    in a '.' stay apart)."""
    S.instanced(16)
    cube = next(o for o in bpy.data.objects if o.type == "MESH" and "Cube" in o.name)
    sphere = next(o for o in bpy.data.objects if o.type == "MESH" and "Sphere" in o.name)
    cube.name, sphere.name = "Cube.001", "Cube_001"
    desc = exporter.export(bpy.context.evaluated_depsgraph_get())
    groups = sorted(k for k in desc if k.startswith("group_"))
    assert groups == sorted([exporter.group_id("Cube.001"), exporter.group_id("Cube_001")])
    assert len(set(groups)) == 2 and all("." not in g for g in groups)
    scene = build.description_scene_dict(desc)
    from styletrace.frontends import api
    sc = api.load_scene(scene)
    assert len(sc.shapes()) >= 3  # the floor and the instances
