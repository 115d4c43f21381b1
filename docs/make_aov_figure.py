"""The error AOVs on the Cornell box: `.venv/bin/python docs/make_aov_figure.py` writes
docs/aovs.png (shown in docs/adaptive.md). Needs the `plots` extra (matplotlib).

Two styles at the first hit with adaptive inner counts 16:64, 16 camera samples per pixel: cel (a
step style: its children go where the mean brightness is near a threshold) and colour map (smooth,
with kinks at its gradient stops and range clamps: its children go where the predicted Eq. 21 bias
is large). Per style: the image, the variance of each pixel's estimate (RGB mean, log scale), the
predicted bias and the children used at the first hit.
"""
import os

import matplotlib
import matplotlib.pyplot as plt
import numpy as np

import styletrace
from styletrace.images import srgb8

styletrace.init()
matplotlib.use("Agg")

SIZE, SPP, INNER = 128, 16, "16:64"
STYLES = ("cel", "color_map")


def main():
    fig, axes = plt.subplots(
        len(STYLES), 4, figsize=(13, 3.4 * len(STYLES)), constrained_layout=True
    )
    for row, style in zip(axes, STYLES):
        image, aovs = styletrace.render(
            "cornell-box",
            style=style,
            spp=SPP,
            inner=INNER,
            width=SIZE,
            height=SIZE,
            aovs=True,
            seed=1,
        )
        var = aovs["variance"].mean(axis=-1)
        row[0].imshow(srgb8(image))
        row[0].set_title(f"{style} {INNER}, {SPP} spp")
        im = row[1].imshow(np.log10(np.maximum(var, 1e-8)), cmap="magma")
        row[1].set_title("log10 variance (pixel)")
        fig.colorbar(im, ax=row[1], shrink=0.8)
        lim = max(float(np.abs(aovs["bias"]).max()), 1e-12)
        im = row[2].imshow(aovs["bias"], cmap="coolwarm", vmin=-lim, vmax=lim)
        row[2].set_title("predicted bias (Eq. 21)")
        fig.colorbar(im, ax=row[2], shrink=0.8)
        im = row[3].imshow(aovs["children"], cmap="viridis", vmin=0, vmax=64)
        row[3].set_title("children at the first hit (mean)")
        fig.colorbar(im, ax=row[3], shrink=0.8)
        for ax in row:
            ax.set_xticks([])
            ax.set_yticks([])
        print(
            f"{style}: mean children {aovs['children'].mean():.1f}, mean variance "
            f"{var.mean():.3g}, "
            f"|bias| max {lim:.3g}",
            flush=True,
        )
    out = os.path.join(os.path.dirname(os.path.abspath(__file__)), "aovs.png")
    fig.savefig(out, dpi=80)
    print(f"wrote {out}")


if __name__ == "__main__":
    main()
