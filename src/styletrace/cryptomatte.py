"""The Cryptomatte standard's ids and metadata: a name's MurmurHash3_x86_32 (seed 0) of its UTF-8
bytes, made a float32 that is never NaN, inf or denormal, its 8 hex digits in the manifest, and
the EXR header keys that name a Cryptomatte type (its 7-digit key, hash, conversion, manifest).

    murmur3_32(b"bunny")              # 0x13851a76, the specification's example
    id_bits("Plane")                  # the float32 bits of the id pixels hold (uint32)
    manifest(["Plane", "Box.001"])    # {"Box.001": "e3a405de", "Plane": "4159b52a"}
    exr_metadata({"CryptoObject": {...}})  # {"cryptomatte/d593dd7/name": "CryptoObject", ...}

Written from the Cryptomatte specification 1.1.0 (Psyop); numpy and the standard library only, so
the EXR writers (`images`) use it too. Docs: docs/passes.md (Cryptomatte).
"""
from __future__ import annotations

import json
from typing import Iterable

import numpy as np

#: the standard's metadata values for the one hash and the one conversion it defines
HASH = "MurmurHash3_32"
CONVERSION = "uint32_to_float32"
_MASK = 0xFFFFFFFF


def _rotl(x: int, r: int) -> int:
    return ((x << r) | (x >> (32 - r))) & _MASK


def _mix(k: int) -> int:
    """A block's scramble before it enters the state."""
    k = (k * 0xCC9E2D51) & _MASK
    return (_rotl(k, 15) * 0x1B873593) & _MASK


def murmur3_32(data: bytes, seed: int = 0) -> int:
    """MurmurHash3_x86_32 (Austin Appleby's, public domain) of `data`.

    Args:
        data: the bytes. seed: the hash's seed (the standard's is 0).

    Returns:
        The hash, an int in [0, 2**32).
    """
    h = seed & _MASK
    whole = len(data) // 4 * 4
    for k in np.frombuffer(data[:whole], dtype="<u4").tolist():
        h ^= _mix(k)
        h = (_rotl(h, 13) * 5 + 0xE6546B64) & _MASK
    tail = data[whole:]
    if tail:  # the last 1 to 3 bytes, little-endian
        h ^= _mix(int.from_bytes(tail, "little"))
    h ^= len(data)
    # the finaliser: every input bit reaches every output bit
    h ^= h >> 16
    h = (h * 0x85EBCA6B) & _MASK
    h ^= h >> 13
    h = (h * 0xC2B2AE35) & _MASK
    return h ^ (h >> 16)


def float_bits(hash32: int) -> int:
    """The standard's uint32_to_float32: the hash's bits as a float32's, the exponent clamped to
    [1, 254] so that no id is 0, a denormal, inf or NaN.

    Args:
        hash32: a 32-bit hash.

    Returns:
        The float32's bits (an int; the hash itself where its exponent is already in range).
    """
    exponent = min(max((hash32 >> 23) & 0xFF, 1), 254)
    return (hash32 & 0x807FFFFF) | (exponent << 23)


def id_bits(name: str) -> int:
    """A name's id as pixels hold it: `float_bits` of the MurmurHash3 of its UTF-8 bytes.

    Args:
        name: an object's or a material's name.

    Returns:
        The float32's bits, an int.
    """
    return float_bits(murmur3_32(name.encode("utf-8")))


def id_float(name: str) -> np.float32:
    """A name's id as a float32 (`id_bits` reinterpreted).

    Args:
        name: the name.

    Returns:
        The float32.
    """
    return np.array([id_bits(name)], dtype=np.uint32).view(np.float32)[0]


def manifest(names: Iterable[str]) -> dict[str, str]:
    """The manifest of some names: each name's id as the specification writes it, the 8 lower-case
    hex digits of the float32's bits.

    Args:
        names: the names (repeats are kept once).

    Returns:
        {name: 8 hex digits}, sorted by name.
    """
    return {name: f"{id_bits(name):08x}" for name in sorted(set(names))}


def type_key(typename: str) -> str:
    """The 7-character key of a Cryptomatte type in the EXR header: the first 7 hex digits of
    its name's MurmurHash3, as Blender and the specification's examples make it.

    Args:
        typename: the type's layer name ('CryptoObject', 'ViewLayer.CryptoObject').

    Returns:
        7 lower-case hex digits.
    """
    return f"{murmur3_32(typename.encode('utf-8')):08x}"[:7]


def exr_metadata(manifests: dict[str, dict[str, str]]) -> dict[str, str]:
    """The EXR header attributes of Cryptomatte types.

    Args:
        manifests: {type name ('CryptoObject'): its manifest (`manifest`)}.

    Returns:
        {'cryptomatte/<type_key>/name' | '/hash' | '/conversion' | '/manifest': value} for each
        type; the manifest as compact JSON.
    """
    out = {}
    for typename, names in manifests.items():
        prefix = f"cryptomatte/{type_key(typename)}/"
        out[prefix + "name"] = typename
        out[prefix + "hash"] = HASH
        out[prefix + "conversion"] = CONVERSION
        out[prefix + "manifest"] = json.dumps(names, separators=(",", ":"), ensure_ascii=False)
    return out


__all__ = ["HASH", "CONVERSION", "murmur3_32", "float_bits", "id_bits", "id_float", "manifest",
           "type_key", "exr_metadata"]
