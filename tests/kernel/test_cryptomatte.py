"""The Cryptomatte passes' parts against outside truth: the hash against the specification's
published manifest and Cycles 5.0's (measured: its manifests of tests/blender/test_cryptomatte.py's
scene), the float conversion's clamps, the ranking filter on known samples, and two walls meeting
in the middle of a pixel column, whose coverages there share each pixel's samples."""
import json
import math

import numpy as np
import pytest

from styletrace.cryptomatte import (
    exr_metadata,
    float_bits,
    id_bits,
    id_float,
    manifest,
    murmur3_32,
    type_key,
)
from styletrace.errors import UsageError
from styletrace.gate import mi
from styletrace.kernel.asset_names import MATERIAL, OBJECT, named_id, names_in
from styletrace.kernel.crypto_ranks import ranks
from styletrace.kernel.data_passes import MANIFEST, render_data_passes
from styletrace.kernel.pass_indices import indices_of, shape_id

#: the specification 1.1.0's example manifests ({"bunny":"13851a76", "default":"42c9679f"},
#: {"bunny_porcelain_mat":"b24b26d4"})
SPEC = {"bunny": 0x13851A76, "default": 0x42C9679F, "bunny_porcelain_mat": 0xB24B26D4}
#: Cycles 5.0's manifests and type keys (bpy, use_pass_cryptomatte_object/material on)
CYCLES = {"Plane": 0x4159B52A, "Box.001": 0xE3A405DE, "Red Mat": 0x7B9DBF6F,
          "default_surface": 0x78D05529, "Blue.é": 0x708029D2, "floor mat": 0xAE1A2893,
          "Sphère": 0xFFF395E7}
KEYS = {"ViewLayer.CryptoObject": "542cafa", "ViewLayer.CryptoMaterial": "c7dbf5e"}


def test_the_hash_is_the_specifications_and_cycles():
    for name, want in {**SPEC, **CYCLES}.items():
        assert murmur3_32(name.encode("utf-8")) == want, name
    for typename, key in KEYS.items():
        assert type_key(typename) == key
    # MurmurHash3_x86_32's own test vectors: the empty input, seeds, a tail of each length
    assert murmur3_32(b"") == 0 and murmur3_32(b"", 1) == 0x514E28B7
    assert murmur3_32(b"\xff\xff\xff\xff") == 0x76293B50
    assert murmur3_32(b"\x21\x43\x65\x87") == 0xF55B516B
    assert murmur3_32(b"\x21\x43\x65") == 0x7E4A8634 and murmur3_32(b"\x21\x43") == 0xA0F7B07A
    assert murmur3_32(b"\x21") == 0x72661CF4


def test_the_float_conversion_clamps_the_exponent_only():
    # 'Sphère' hashes to an exponent of 255: its float is the largest exponent's, sign kept
    assert float_bits(0xFFF395E7) == 0xFF7395E7 and id_bits("Sphère") == 0xFF7395E7
    assert float_bits(0x00000000) == 0x00800000 and float_bits(0x80000001) == 0x80800001
    assert float_bits(0x7F800000) == 0x7F000000 and float_bits(0x4159B52A) == 0x4159B52A
    rng = np.random.default_rng(3)
    hashes = rng.integers(0, 2**32, 20000, dtype=np.uint64).tolist() + [0, 2**32 - 1]
    floats = np.array([float_bits(h) for h in hashes], np.uint32).view(np.float32)
    assert np.isfinite(floats).all() and (np.abs(floats) >= np.finfo(np.float32).tiny).all()
    assert id_float("Plane") == np.float32(13.606729507446289)


def test_manifest_and_metadata():
    got = manifest(["Sphère", "Plane", "Plane"])
    assert got == {"Plane": "4159b52a", "Sphère": "ff7395e7"}  # the float's bits, per the spec
    meta = exr_metadata({"ViewLayer.CryptoObject": got})
    prefix = "cryptomatte/542cafa/"
    assert meta == {prefix + "name": "ViewLayer.CryptoObject", prefix + "hash": "MurmurHash3_32",
                    prefix + "conversion": "uint32_to_float32",
                    prefix + "manifest": json.dumps(got, separators=(",", ":"),
                                                    ensure_ascii=False)}


def test_ids_carry_the_names_beside_the_indices():
    ident = shape_id(named_id("shape_3", "Cube.001", "Mat é"), 7, 5)
    assert names_in(ident) == ("Cube.001", "Mat é") and indices_of(ident) == (7, 5)
    assert names_in(named_id("g_0", "", "x")) == ("", "x")
    for plain in ("shape_3", "shape_3__ob7", "", "a__cmzz_00", "a__cm6_"):
        assert names_in(plain) is None, plain


def test_ranks_of_known_samples():
    bits = np.array([[5, 5, 0, 7], [0, 0, 0, 0], [9, 9, 9, 9], [3, 4, 5, 6]], np.uint32)
    out = ranks(bits, levels=3)
    assert out.shape == (4, 6)
    np.testing.assert_array_equal(out[:, 0::2].view(np.uint32),
                                  [[5, 7, 0], [0, 0, 0], [9, 0, 0], [3, 4, 5]])
    np.testing.assert_array_equal(out[:, 1::2], [[0.5, 0.25, 0], [0, 0, 0], [1, 0, 0],
                                                 [0.25, 0.25, 0.25]])
    many = ranks(np.arange(1, 9, dtype=np.uint32)[None].repeat(2, 0), levels=6)
    assert (many[:, 1::2] == 0.125).all()  # 8 ids, 6 kept: the two dropped lose their share
    assert ranks(bits[:, :1]).shape == (4, 12)  # fewer samples than levels: the rest empty
    with pytest.raises(UsageError, match="bad value 0 for the Cryptomatte levels"):
        ranks(bits, levels=0)


T = mi.ScalarTransform4f
W, H, FOV, D = 32, 24, 40.0, 10.0
F = (W / 2) / math.tan(math.radians(FOV / 2))


def two_walls():
    """Two walls at z = 0 meeting at x0, the centre line of pixel column 16; the left one
    carries Blender's names in its id, the right one is a plain Mitsuba shape with a BSDF id."""
    x0 = 0.5 * D / F
    cam = T().look_at(origin=[0, 0, D], target=[0, 0, 0], up=[0, 1, 0])

    def wall(a, b, **extra):
        return {"type": "rectangle", **extra,
                "to_world": T().translate([(a + b) / 2, 0, 0]).scale([(b - a) / 2, 50, 1])}
    return mi.load_dict({
        "type": "scene", "blue": {"type": "diffuse"},
        named_id("left", "Cube.001", "Red é"): wall(-50, x0),
        "right": wall(x0, 50, bsdf={"type": "ref", "id": "blue"}),
        "sensor": {"type": "perspective", "fov": FOV, "to_world": cam,
                   "film": {"type": "hdrfilm", "width": W, "height": H}}})


def test_two_walls_share_the_pixels_where_they_meet():
    spp = 256
    out = render_data_passes(two_walls(), ["crypto_object", "crypto_material"], spp, seed=5)
    assert out[MANIFEST] == {OBJECT: manifest(["Cube.001", "right"]),
                             MATERIAL: manifest(["Red é", "blue"])}
    for key, (left, right) in (("crypto_object", ("Cube.001", "right")),
                               ("crypto_material", ("Red é", "blue"))):
        ob = out[key]
        assert ob.shape == (H, W, 12)
        ids, cov = ob[..., 0::2].view(np.uint32), ob[..., 1::2]
        np.testing.assert_array_equal(cov.sum(-1), 1)  # no sample meets nothing
        assert (ids[:, :16, 0] == id_bits(left)).all() and (cov[:, :16, 0] == 1).all()
        assert (ids[:, 17:, 0] == id_bits(right)).all() and (cov[:, 17:, 0] == 1).all()
        assert (cov[..., 2:] == 0).all() and (ids[..., 2:] == 0).all()
        # column 16: each wall covers half the pixel; 256 samples: 0.5 within 5 sigma (0.16)
        mine = {id_bits(left): 0.0, id_bits(right): 0.0}
        for r in range(2):
            for i, c in zip(ids[:, 16, r], cov[:, 16, r]):
                mine[int(i)] += c / H
        assert set(mine) == {id_bits(left), id_bits(right)}
        assert all(abs(v - 0.5) < 0.16 / math.sqrt(H) + 0.01 for v in mine.values())
        assert (cov[:, 16, 0] >= cov[:, 16, 1]).all() and (cov[:, 16, 1] > 0).all()
