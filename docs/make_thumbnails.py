"""Render the thumbnail of every style for docs/styles.md: `.venv/bin/python
docs/make_thumbnails.py [STYLE ...]` (no names: every style, and docs/teaser.png).

Each style is rendered on the built-in dragon scene at 160x160 with its default parameters except
those in OVERRIDES, and its default inner sample count (at least 8, so affine styles are not shown
at 1). A style whose values are not colours is shown through DISPLAY.
"""
import os
import sys

import styletrace
from styletrace.images import write_image
from styletrace.styles import style_class, style_names

styletrace.init()

SIZE, SPP = 160, 32
# spacings in the dragon's units (1 = its height) and brightness ranges of the dragon scene, so that
# lit and shaded parts differ; cel gets three bands for the same reason
OVERRIDES = {
    "hatching": {"spacing": 0.05, "u_min": 0.05, "u_max": 0.45},
    "halftone": {"spacing": 0.05, "u_min": 0.05, "u_max": 0.6},
    "cel": {"thresholds": "0.2,0.45", "levels": "0.1,0.4,0.9"},
}


#: a debug style's values mapped to colours for its thumbnail: coordinate's (s_x, s_y, method), s in
#: pixels from the image centre, becomes (s_x / SIZE + 0.5, s_y / SIZE + 0.5, method / 5)
DISPLAY = {
    "coordinate": lambda img: img / [SIZE, SIZE, 5] + [0.5, 0.5, 0.0],
}

#: styles side by side in docs/teaser.png, the README's first picture
TEASER = ("identity", "cel", "color_map", "hatching", "tie_dye")


def main(names=()):
    import numpy as np

    out = os.path.join(os.path.dirname(__file__), "styles")
    os.makedirs(out, exist_ok=True)
    images = {}
    for name in names or style_names():
        inner = max(style_class(name).default_inner, 8)
        img = styletrace.render("dragon", style=name, spp=SPP, inner=inner, width=SIZE, height=SIZE,
                                **OVERRIDES.get(name, {}))
        img = DISPLAY.get(name, lambda x: x)(img)
        write_image(img, os.path.join(out, f"{name}.png"))
        images[name] = img
        print(name, flush=True)
    if names:  # a few thumbnails re-rendered: the teaser stays
        return
    write_image(
        np.concatenate([images[n] for n in TEASER], axis=1),
        os.path.join(os.path.dirname(__file__), "teaser.png"),
    )


if __name__ == "__main__":
    main(tuple(sys.argv[1:]))
