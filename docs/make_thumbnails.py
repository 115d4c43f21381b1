"""Render the thumbnail of every style for docs/styles.md: `python docs/make_thumbnails.py`.

Each style is rendered on the built-in dragon scene at 160x160 with its default parameters (the
hatching and half-tone spacings are scaled to the dragon's unit height) and default inner sample count.
"""
import os
import sys

sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "src"))

import styletrace  # noqa: E402
from styletrace.cli import write_image  # noqa: E402
from styletrace.styles import get, names  # noqa: E402

SIZE, SPP = 160, 8
OVERRIDES = {"hatching": {"spacing": 0.025}, "halftone": {"spacing": 0.03}}


def main():
    out = os.path.join(os.path.dirname(__file__), "styles")
    os.makedirs(out, exist_ok=True)
    for name in names():
        inner = max(get(name).default_inner, 1)
        img = styletrace.render("dragon", style=name, spp=SPP, inner=inner, width=SIZE, height=SIZE,
                                **OVERRIDES.get(name, {}))
        write_image(img, os.path.join(out, f"{name}.png"))
        print(name, flush=True)


if __name__ == "__main__":
    main()
