"""docs/lines.png: the two feature-line gallery setups side by side (docs/lines.md).

    PYTHONPATH=src python docs/make_lines_figure.py [SIZE] [SPP]
"""
from __future__ import annotations

import os
import sys

import numpy as np

import styletrace
from styletrace.frontends import api, gallery


def main(size: int = 192, spp: int = 16) -> None:
    styletrace.init()
    images = []
    for key in ("lines", "lines_mirror"):
        setup = next(s for s in gallery.SETUPS if s.key == key)
        integ = api.make_integrator(
            setup.style, inner=setup.counts[0], **setup.integrator, **setup.params
        )
        images.append(
            api.render(api.load_scene(setup.scene, size, size), integrator=integ, spp=spp, seed=1)
        )
    gap = np.ones((size, 4, 3), np.float32)
    api.write_image(np.concatenate([images[0], gap, images[1]], axis=1),
                    os.path.join(os.path.dirname(os.path.abspath(__file__)), "lines.png"))


if __name__ == "__main__":
    main(*map(int, sys.argv[1:3]))
