"""Contact sheet of the scene-feature corpus (issue 18): `.venv/bin/python
docs/make_scene_corpus.py` writes docs/scene_corpus.png (shown in docs/scenes.md).

One row per scene of `tests/corpus/scenes.py` (written into a temporary folder, assets included),
labelled with its name and the features it covers; columns: physically based (`identity`), GI cel
shading, hatching, colour map, and cel with feature lines (`--lines`). Every style is at its
defaults, so the scene-relative 'auto' values (cel thresholds, the hatching and colour-map
brightness ranges, hatching's screen spacing on the orthographic and thin-lens sensors) are resolved
per scene as `styletrace render` resolves them, and each scene keeps its own integrator's max_depth
/ hide_emitters (`api.render`). Images are sRGB, clamped.
"""
import os
import sys
import tempfile
import textwrap
import time

import styletrace
from styletrace.frontends import api
from styletrace.images import srgb8, write_bytes_atomically

HERE = os.path.dirname(os.path.abspath(__file__))
styletrace.init()

SIZE, SPP, INNER, SEED = 128, 16, 8, 1
#: (column title, render keywords)
COLUMNS = [
    ("identity (physically based)", {"style": "identity", "inner": 1}),
    ("cel", {"style": "cel"}),
    ("hatching", {"style": "hatching"}),
    ("colour map", {"style": "color_map"}),
    ("cel + feature lines", {"style": "cel", "lines": True}),
]


def corpus_scenes():
    """`tests/corpus/scenes.py`: the corpus lives with its tests."""
    sys.path.insert(0, os.path.join(HERE, "..", "tests"))
    from corpus import scenes
    return scenes


def render_all(folder):
    scenes = corpus_scenes()
    images = {}
    for name in scenes.SCENES:
        xml = str(scenes.write_scene(name, os.path.join(folder, name)))
        for title, kwargs in COLUMNS:
            t = time.time()
            kwargs = {"inner": INNER, **kwargs}
            images[name, title] = api.render(
                xml, spp=SPP, seed=SEED, width=SIZE, height=SIZE, **kwargs
            )
            print(f"{name:>13} {title:>28}: {time.time() - t:5.1f} s", flush=True)
    return images


def figure(images, path):
    import io

    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    scenes = corpus_scenes()
    rows, cols = len(scenes.SCENES), len(COLUMNS)
    label_w, cell = 2.2, 1.75  # inches: the label column, one image
    fig, axes = plt.subplots(rows, cols + 1, figsize=(label_w + cols * cell, rows * cell + 0.4),
                             gridspec_kw={"width_ratios": [label_w / cell] + [1] * cols})
    for r, name in enumerate(scenes.SCENES):
        label = axes[r, 0]
        label.axis("off")
        label.text(
            0.0, 0.62, name, fontsize=10, fontweight="bold", va="center", transform=label.transAxes
        )
        label.text(
            0.0,
            0.5,
            textwrap.fill(scenes.FEATURES.get(name, ""), 32),
            fontsize=7.2,
            va="top",
            color="#333333",
            transform=label.transAxes,
        )
        for c, (title, _) in enumerate(COLUMNS):
            ax = axes[r, c + 1]
            ax.imshow(srgb8(images[name, title][..., :3]), interpolation="nearest")
            ax.set_xticks([])
            ax.set_yticks([])
            if r == 0:
                ax.set_title(title, fontsize=9)
    fig.subplots_adjust(left=0.01, right=0.995, top=1 - 0.35 / (rows * cell + 0.4), bottom=0.005,
                        wspace=0.04, hspace=0.06)
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=110)
    write_bytes_atomically(buf.getvalue(), path)
    plt.close(fig)


def main():
    with tempfile.TemporaryDirectory() as folder:
        images = render_all(folder)
    out = os.path.join(HERE, "scene_corpus.png")
    figure(images, out)
    print("wrote", out)


if __name__ == "__main__":
    main()
