"""Cel on an interior at the defaults, with the denoised expectation's uncertainty at 0.3, 0.1 and
0 (the default): `.venv-blender/bin/python docs/make_uncertainty_figure.py` writes
docs/uncertainty.png (shown in docs/design/expectation_denoising.md). Needs bpy (the Blender venv)
and matplotlib.

The scene is tests/blender/scenes.py's `interior` (a room lit through a window) at 512 x 512,
exported to Mitsuba XML by the add-on's exporter and rendered by `styletrace.render` with every
default (Samples 16: four camera samples of four children, Denoise expectation, 16 coverage points
per pixel) but `denoise_uncertainty`. The seconds of each render are printed.
"""
import io
import os
import sys
import tempfile
import time

import bpy
import matplotlib
import matplotlib.pyplot as plt

import styletrace
import styletrace.blender as addon
from styletrace.images import srgb8, write_bytes_atomically

matplotlib.use("Agg")
HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(os.path.dirname(HERE), "tests", "blender"))
import scenes  # noqa: E402  (tests/blender on the path first)

SIZE = 512
VALUES = (0.3, 0.1, 0.0)


def main():
    addon.register()
    scenes.interior(SIZE)
    cells = []
    with tempfile.TemporaryDirectory() as tmp:
        xml = os.path.join(tmp, "interior.xml")
        bpy.ops.styletrace.export_xml(filepath=xml)
        for u in VALUES:
            start = time.perf_counter()
            img = styletrace.render(xml, style="cel", denoise="expectation",
                                    denoise_uncertainty=u)
            print(f"uncertainty {u}: {time.perf_counter() - start:.2f} s")
            cells.append((u, img[..., :3]))
    fig, axes = plt.subplots(1, len(cells), figsize=(5 * len(cells), 5.4), constrained_layout=True)
    for ax, (u, img) in zip(axes, cells):
        ax.imshow(srgb8(img))
        label = "the default" if u == 0 else "averaged over D's error"
        ax.set_title(f"uncertainty {u} ({label})", fontsize=11)
        ax.axis("off")
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=100)
    write_bytes_atomically(buf.getvalue(), os.path.join(HERE, "uncertainty.png"))


if __name__ == "__main__":
    main()
