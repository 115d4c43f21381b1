"""A scene description (`exporter`) -> a Mitsuba 3 XML file that `styletrace render` accepts, with
each mesh in a PLY file and each image in an EXR file in a folder next to it (`<name>_files/`).

Meshes are written with `mi.Mesh.write_ply` from the same in-memory mesh F12 renders, and images as
float32 EXR, so the file renders the same scene; with the same seed and pass split the images are
equal (tests/blender/test_xml.py).
"""
from __future__ import annotations

import os
from typing import Any
from xml.sax.saxutils import quoteattr

import numpy as np

from styletrace.kernel.asset_names import names_in
from styletrace.kernel.pass_indices import indices_of

TAGS = {
    "perspective": "sensor",
    "orthographic": "sensor",
    "thinlens": "sensor",
    "point": "emitter",
    "spot": "emitter",
    "directional": "emitter",
    "area": "emitter",
    "constant": "emitter",
    "envmap": "emitter",
    "portal": "emitter",
    "rectangle": "shape",
    "disk": "shape",
    "blender_mesh": "shape",
    "instance": "shape",
    "shapegroup": "shape",
    "bitmap": "texture",
    "hdrfilm": "film",
    "box": "rfilter",
    "independent": "sampler",
    "owen_sobol": "sampler",
    "stylized": "integrator",
}
POINTS = {"position"}
VECTORS = {"direction"}



def _marked(key: str) -> bool:
    """Whether a description's key is an id the XML file keeps: it carries a shape's names
    (`kernel.asset_names`) or pass indices (`kernel.pass_indices`)."""
    return names_in(key) is not None or any(indices_of(key))

class Writer:
    """Writes one description as a Mitsuba XML file, its meshes and images in `<name>_files/`.

    Args:
        path: the XML file's path.
    """
    def __init__(self, path: str):
        self.path = os.path.abspath(path)
        base = os.path.splitext(os.path.basename(path))[0]
        self.folder_name = f"{base}_files"
        self.folder = os.path.join(os.path.dirname(self.path), self.folder_name)
        self.count = 0
        self.lines: list[str] = []

    def _file(self, ext: str) -> tuple[str, str]:
        os.makedirs(self.folder, exist_ok=True)
        self.count += 1
        name = f"{self.count:04d}{ext}"
        return os.path.join(self.folder, name), f"{self.folder_name}/{name}"

    def _emit(self, depth: int, text: str) -> None:
        self.lines.append("    " * depth + text)

    def _value(self, name: str, value: Any, depth: int) -> None:
        n = quoteattr(name)
        if isinstance(value, np.ndarray) and value.shape == (4, 4):
            flat = " ".join(repr(float(v)) for v in value.reshape(-1))
            self._emit(depth, f'<transform name={n}><matrix value="{flat}"/></transform>')
        elif isinstance(value, dict):
            # a shape in a shapegroup keeps an id that carries its names or pass indices
            self._object(value, depth, name, ident=name if _marked(name) else "")
        elif isinstance(value, bool):
            self._emit(depth, f'<boolean name={n} value="{str(value).lower()}"/>')
        elif isinstance(value, (int, np.integer)):
            self._emit(depth, f'<integer name={n} value="{int(value)}"/>')
        elif isinstance(value, (float, np.floating)):
            self._emit(depth, f'<float name={n} value="{float(value)!r}"/>')
        elif isinstance(value, (list, tuple)) and name in POINTS | VECTORS:
            tag = "point" if name in POINTS else "vector"
            x, y, z = (float(v) for v in value)
            self._emit(depth, f'<{tag} name={n} x="{x!r}" y="{y!r}" z="{z!r}"/>')
        else:
            self._emit(depth, f"<string name={n} value={quoteattr(str(value))}/>")

    def _object(self, d: dict, depth: int, name: str = "", ident: str = "") -> None:
        kind = d["type"]
        if kind == "rgb":
            r, g, b = (float(v) for v in d["value"])
            self._emit(depth, f'<rgb name={quoteattr(name)} value="{r!r}, {g!r}, {b!r}"/>')
            return
        if kind == "ref":
            self._emit(depth, f'<ref id={quoteattr(d["id"])}/>')
            return
        tag = TAGS.get(kind, "bsdf")
        attrs = f" name={quoteattr(name)}" if tag == "texture" else ""
        attrs += f" id={quoteattr(ident)}" if ident else ""
        body = dict(d)
        body.pop("type")
        if kind == "blender_mesh":
            kind = "ply"
            path, rel = self._file(".ply")
            self._ply(body.pop("part"), body.pop("name"), path)
            body = {"filename": rel, **body}
        if "data" in body:
            path, rel = self._file(".exr")
            self._exr(body.pop("data"), path)
            body = {"filename": rel, **body}
        self._emit(depth, f"<{tag} type={quoteattr(kind)}{attrs}>")
        for key, value in body.items():
            self._value(key, value, depth + 1)
        self._emit(depth, f"</{tag}>")

    @staticmethod
    def _ply(part, name: str, path: str) -> None:
        from styletrace.blender.mesh import to_mitsuba
        to_mitsuba(part, name).write_ply(path)

    @staticmethod
    def _exr(data: np.ndarray, path: str) -> None:
        import mitsuba as mi
        mi.Bitmap(np.ascontiguousarray(data, dtype=np.float32)).write(path)

    def write(self, desc: dict, integrator: dict | None) -> str:
        """Write the file (atomically: a temporary file, then a rename) and its meshes and images.

        Args:
            desc: the scene description (`exporter.export`).
            integrator: the `stylized` integrator's properties, or None for none.

        Returns:
            The file's absolute path.
        """
        self.lines = [
            '<?xml version="1.0" encoding="utf-8"?>',
            "<!-- written by styletrace.blender (the Blender add-on); render with `styletrace "
            "render` -->",
            '<scene version="3.0.0">',
        ]
        if integrator is not None:
            self._object({"type": "stylized", **integrator}, 1)
        for key, value in desc.items():
            if key == "type":
                continue
            # a shapegroup's id is referenced; a shape's carries its names and pass indices
            kept = value.get("type") == "shapegroup" or _marked(key)
            self._object(value, 1, ident=key if kept else "")
        self.lines.append("</scene>")
        tmp = self.path + ".tmp"
        with open(tmp, "w", encoding="utf-8") as f:
            f.write("\n".join(self.lines) + "\n")
        os.replace(tmp, self.path)
        return self.path


def write(desc: dict, path: str, integrator: dict | None = None) -> str:
    """Write `desc`, with the `stylized` integrator's properties `integrator`, to XML file `path`.

    Args:
        desc: the scene description. path: the XML file.
        integrator: the integrator's properties (None: no integrator element).

    Returns:
        The file's absolute path.
    """
    return Writer(path).write(desc, integrator)
