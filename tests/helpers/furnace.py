"""The furnace scene as a test fixture: exact first-hit radiance I = rho * E on the sphere.

By symmetry every visible point of the sphere has the same distribution of path-traced estimates, so
the pixels inside the silhouette are independent draws of one estimator (spp = 1 gives one per
pixel).
"""
import numpy as np

from styletrace.frontends.api import load_scene, make_integrator, passes
from styletrace.scene.builtin import FURNACE_ALBEDO, FURNACE_RADIANCE

I = np.array(FURNACE_ALBEDO) * FURNACE_RADIANCE


def scene(res):
    return load_scene("furnace", res, res)


def sphere_mask(res):
    """The central 85% of the sphere's projected disk (camera at distance 4, fov 35 deg on the
    smaller axis)."""
    rpix = np.tan(np.arcsin(0.25)) / np.tan(np.radians(17.5)) * res / 2
    yy, xx = np.mgrid[0:res, 0:res]
    c = (res - 1) / 2
    return (xx - c) ** 2 + (yy - c) ** 2 < (0.85 * rpix) ** 2


def draws(scene, mask, style, n, seeds, seed0, **kw):
    """One value per sphere pixel per seed, each from one camera sample; float64 (count, 3)."""
    integ = make_integrator(style, inner=n, **kw)
    return np.concatenate([list(passes(scene, integ, 1, seed=seed0 + s))[-1].image[mask]
                           for s in range(seeds)]).astype(np.float64)


def resolved(scene, style, **kw):
    """The style as a render of `scene` uses it: its scene-relative 'auto' values (the tone
    styles' exposure, from the pilot) pinned, as `passes` pins them."""
    from styletrace.frontends.api import resolve_defaults
    return resolve_defaults(scene, make_integrator(style, **kw))[0].settings.slot.style


def z_score(vals, exact):
    return (vals.mean(0) - exact) / (vals.std(0, ddof=1) / np.sqrt(len(vals)))
