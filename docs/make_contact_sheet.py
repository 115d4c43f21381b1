"""Contact sheet of every style at its defaults on three scenes of very different scale:
`.venv/bin/python docs/make_contact_sheet.py` writes docs/defaults_contact_sheet.png (shown in
docs/styles.md).

Scenes: the built-in cornell-box (about 2 units across), the built-in dragon (unit height) and the
Cornell box scaled x100 with its light x0.1 (`assets.scenes.scaled`: 200 units across and a tenth as
bright), so the scales differ by 200x and the brightness by 10x. Every style is rendered with no
parameter given: its scene-relative 'auto' values are resolved per scene (`scene.defaults`) and
printed here.
"""
import os

import numpy as np

import styletrace
from styletrace.frontends import api
from styletrace.images import write_image
from styletrace.scene.builtin import cornell_box, dragon, scaled
from styletrace.styles import style_class, style_names

styletrace.init()

SIZE, SPP, GAP = 96, 16, 4
SCENES = {
    "cornell-box": lambda: cornell_box(SIZE, SIZE),
    "dragon": lambda: dragon(SIZE, SIZE),
    "cornell-box x100, light x0.1": lambda: scaled(cornell_box(SIZE, SIZE), 100.0, light=0.1),
}


def main():
    rows = []
    for scene_name, make in SCENES.items():
        row = []
        for name in style_names():
            inner = max(style_class(name).default_inner, 8)
            scene = api.load_scene(make())
            integrator, chosen = api.resolve_defaults(
                scene, api.make_integrator(style=name, inner=inner)
            )
            print(f"{scene_name:>28} {name:>10}: {chosen or '-'}", flush=True)
            img = None
            for prog in api.passes(scene, integrator, SPP, seed=1):
                img = prog.image
            row.append(np.pad(img, ((GAP, GAP), (GAP, GAP), (0, 0)), constant_values=1.0))
        rows.append(np.concatenate(row, axis=1))
    sheet = np.concatenate(rows, axis=0)
    write_image(sheet, os.path.join(os.path.dirname(__file__), "defaults_contact_sheet.png"))
    print("columns:", ", ".join(style_names()))


if __name__ == "__main__":
    main()
