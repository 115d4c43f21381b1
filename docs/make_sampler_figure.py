"""Independent samples against the `owen_sobol` sequence on the dragon:
`.venv/bin/python docs/make_sampler_figure.py` writes docs/sampler.png (shown in
docs/design/sequence_sampler.md). Needs the `plots` extra (matplotlib).

Identity, 16 camera samples per pixel of one child, denoising off, seed 1, 192 x 192: the same
integrator with the scene's sampler `independent`, then `owen_sobol` (its default, with spatial
light selection as `auto` gives it), and a reference of 2048 samples; each titled with its mean
squared error against the reference.
"""
import os

import matplotlib
import matplotlib.pyplot as plt
import numpy as np

import styletrace
from styletrace.frontends import api
from styletrace.images import srgb8

styletrace.init()
matplotlib.use("Agg")

SIZE, SPP, REF_SPP = 192, 16, 2048


def render(sampler: str, spp: int, seed: int) -> np.ndarray:
    scene = api.load_scene("dragon", SIZE, SIZE, sampler=sampler)
    integ = api.make_integrator("identity", inner=1)
    return list(api.passes(scene, integ, spp, seed=seed))[-1].image[..., :3]


def main():
    ref = render("owen_sobol", REF_SPP, 99)
    panels = [("independent", render("independent", SPP, 1)),
              ("owen_sobol", render("owen_sobol", SPP, 1)),
              (f"reference, {REF_SPP} samples", ref)]
    fig, axes = plt.subplots(1, 3, figsize=(12, 4.3), constrained_layout=True)
    for ax, (name, img) in zip(axes, panels):
        ax.imshow(srgb8(img))
        mse = float(np.mean((img.astype(np.float64) - ref) ** 2))
        ax.set_title(name if "reference" in name else f"{name}, {SPP} samples: MSE {mse:.1e}")
        ax.axis("off")
    out = os.path.join(os.path.dirname(os.path.abspath(__file__)), "sampler.png")
    fig.savefig(out, dpi=100)
    print(f"wrote {out}")


if __name__ == "__main__":
    main()
