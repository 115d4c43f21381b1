"""Blender 3.x's Principled BSDF, read by 4.x's names and meaning (`materials.principled_sockets`):
the bpy here is 5.0, so the 3.x node is a stand-in with 3.x's input names and defaults."""
from types import SimpleNamespace

import numpy as np
import scenes as S

from styletrace.blender import materials as M


def socket(value):
    """An unlinked input holding `value` as Blender does: in float32."""
    value = (tuple(float(np.float32(v)) for v in value) if isinstance(value, tuple)
             else float(np.float32(value)))
    return SimpleNamespace(default_value=value, is_linked=False, links=[])


def node_3x(**values):
    """A Principled BSDF as Blender 3.4 makes it (its defaults), with `values` set by 3.x name."""
    inputs = {"Base Color": (0.8, 0.8, 0.8, 1.0), "Metallic": 0.0, "Specular": 0.5,
              "Specular Tint": 0.0, "Roughness": 0.5, "IOR": 1.45, "Transmission": 0.0,
              "Emission": (0.0, 0.0, 0.0, 1.0), "Emission Strength": 1.0, "Alpha": 1.0}
    inputs.update(values)
    return SimpleNamespace(bl_idname="ShaderNodeBsdfPrincipled",
                           inputs={k: socket(v) for k, v in inputs.items()})


def export(node):
    ctx = M.MaterialContext(warn=print)
    out = M.principled(node, ctx, SimpleNamespace(name="m"))
    assert not ctx.unsupported
    return out


def same(a, b):
    """Whether two exports are equal, to the bit."""
    if isinstance(a, dict):
        return isinstance(b, dict) and a.keys() == b.keys() and all(same(a[k], b[k]) for k in a)
    if isinstance(a, (tuple, list)):
        return isinstance(b, (tuple, list)) and len(a) == len(b) and all(map(same, a, b))
    if isinstance(a, np.ndarray):
        return isinstance(b, np.ndarray) and np.array_equal(a, b)
    return type(a) is type(b) and a == b


def test_interiors_materials_export_as_on_blender_4():
    """tests/blender/scenes.py's `interior` built on 3.x (Specular for Specular IOR Level, the
    other inputs at 3.x's defaults) exports what the same scene exports on 4.x and later."""
    S.reset(16)
    for colour, rough, spec, metal in (((0.75, 0.72, 0.65), 0.9, 0.5, 0.0),
                                       ((0.45, 0.28, 0.15), 0.25, 0.5, 0.0),
                                       ((0.9, 0.9, 0.9), 0.02, 0.5, 1.0),
                                       ((0.8, 0.2, 0.1), 0.3, 0.0, 0.0)):
        _, new = S.material("m", "ShaderNodeBsdfPrincipled", **{
            "Base Color": colour, "Roughness": rough, "Specular IOR Level": spec,
            "Metallic": metal})
        old = node_3x(**{"Base Color": (*colour, 1.0), "Roughness": rough, "Specular": spec,
                         "Metallic": metal})
        assert M.principled_sockets(new)[1] is None
        assert M.principled_sockets(old)[1] == M.PRINCIPLED_3X_IOR
        assert same(export(old), export(new)), (colour, rough, spec, metal)


def test_f0_from_specular_and_the_ior_for_transmission_only():
    """F0 = 0.08 x Specular whatever the IOR; the IOR refracts the transmission."""
    for spec in (0.25, 1.0):
        bsdf, _, _ = export(node_3x(Specular=spec, IOR=1.33, Transmission=0.5, Roughness=0.2))
        assert bsdf["type"] == "blendbsdf" and np.isclose(bsdf["weight"], 0.5)
        eta = bsdf["a"]["b"]["eta"]  # the dielectric base's specular layer
        assert np.isclose(((eta - 1) / (eta + 1)) ** 2, 0.08 * spec)
        assert bsdf["b"]["type"] == "roughdielectric" and np.isclose(bsdf["b"]["int_ior"], 1.33)


def test_specular_tint_and_emission():
    base = np.array([0.8, 0.2, 0.1])
    white, _, _ = export(node_3x(**{"Base Color": (*base, 1.0)}))
    tinted, emitter, _ = export(node_3x(**{
        "Base Color": (*base, 1.0), "Specular Tint": 0.5, "Emission": (1.0, 0.5, 0.25, 1.0),
        "Emission Strength": 4.0}))
    # 3.x tints F0 by (1 - t) + t x base / luminance(base); the layer as 4.x's tint colour does
    ratio = (np.asarray(tinted["b"]["specular_reflectance"]["data"]).reshape(3)
             / white["b"]["specular_reflectance"])
    assert np.allclose(ratio, 0.5 + 0.5 * base / np.dot(base, M.LUMA), rtol=1e-5)
    assert np.allclose(emitter["radiance"]["value"], (4.0, 2.0, 1.0))
    texel = np.array([[[0.5, 0.25, 0.0], [0.0, 0.0, 0.0]]], np.float32)
    tex = M.principled_3x_tint(1.0, M.texture(texel))["data"]
    assert np.allclose(tex[0, 0], texel[0, 0] / np.dot(texel[0, 0], M.LUMA))
    assert np.allclose(tex[0, 1], 1.0)  # black: untinted, as Cycles 3.x
