"""Tone styles follow the brightness of what is seen through glass and in a scattering medium as
they do on surfaces (issue 37; kernel/integrator.py, kernel/volume.py: with first_hit a camera
ray's first collision in a medium is a stylized vertex).

The scene: a diffuse plane whose albedo ramps from 0.02 to 0.9 across the image, under a white sky,
seen directly in the upper rows and in the lower rows through a slab in front of it: glass, glass
holding a dense medium (glass-of-milk's case), a dense medium in a `null` box whose albedo follows
the same ramp, or a thin fog in a `null` box. The measure is the panel's (`measures.
tone_correlation`, the rank correlation of the blurred display luminance with the identity
render's): over the direct rows alone, and over the direct and the slab's rows together, where a
style that maps the slab's pixels by another rule than the plane's loses rank agreement.
"""
import numpy as np
import pytest

import styletrace
from styletrace import measures
from styletrace.gate import mi

T = mi.ScalarTransform4f
RES = 48
#: rows seen directly, and through the slab (its edges left out: they blend the two)
DIRECT, SLAB = slice(2, 19), slice(30, 44)
#: the identity reference's camera samples (denoise off, as every test render here)
REF_SPP = 256
#: The largest loss of rank agreement allowed over the slab's rows. Measured with the fix over seeds
#: 0..5: the mean loss is at most 0.058 (gamma in the dense medium, whose children are noisy at one
#: camera sample) and its seed-to-seed standard deviation at most 0.016, in every case here;
#: 0.058 + 4 x 0.016 ~ 0.12. Before the fix (medium collisions unstylized) the loss was 0.26-0.35 in
#: the dense medium and 0.22-0.46 in the fog; through glass it was as now.
MAX_LOSS = 0.12


def ramp(n: int = 32) -> np.ndarray:
    x = np.linspace(0.0, 1.0, n)
    return 0.9 * np.exp(np.log(0.02 / 0.9) * (1.0 - x))


def scene(slab: str) -> dict:
    """The ramp plane (z = 0) seen from z = 6, the slab in front of its lower half."""
    texture = mi.Bitmap(np.tile(ramp()[None, :, None], (2, 1, 3)).astype(np.float32))
    d = {
        "type": "scene",
        "sensor": {
            "type": "perspective",
            "fov": 30,
            "to_world": T().look_at(origin=[0, 0, 6], target=[0, 0, 0], up=[0, 1, 0]),
            "sampler": {"type": "independent", "sample_count": 16},
            "film": {"type": "hdrfilm", "width": RES, "height": RES, "rfilter": {"type": "box"}},
        },
        "sky": {"type": "constant", "radiance": {"type": "rgb", "value": [1.0, 1.0, 1.0]}},
        "plane": {
            "type": "rectangle",
            "to_world": T().scale([3, 3, 1]),
            "bsdf": {"type": "diffuse", "reflectance": {
                "type": "bitmap", "bitmap": texture, "raw": True, "filter_type": "nearest"}},
        },
    }
    box = T().translate([0, -1.0, 0.6]) @ T().scale([3, 0.8, 0.5])
    if slab == "glass":
        glass = {"type": "dielectric", "int_ior": 1.5}
        d["slab"] = {"type": "cube", "to_world": box, "bsdf": glass}
        return d
    if slab == "fog":
        d["medium"] = {"type": "homogeneous", "sigma_t": 0.7, "albedo": 0.5}
    else:
        # optical depth 10 across the slab, albedo following the plane's ramp: the medium is what
        # is seen
        grid = np.tile(np.sqrt(ramp())[None, None, :, None], (2, 2, 1, 1)).astype(np.float32)
        unit = box @ T().translate([-1, -1, -1]) @ T().scale(2)
        d["medium"] = {
            "type": "heterogeneous",
            "scale": 10.0,
            "sigma_t": {"type": "gridvolume", "to_world": unit,
                        "grid": mi.VolumeGrid(np.ones((2, 2, 2, 1), np.float32))},
            "albedo": {"type": "gridvolume", "to_world": unit, "grid": mi.VolumeGrid(grid)},
        }
    # in glass the stylized vertex is the glass (as in glass-of-milk); behind a `null` boundary it
    # is the medium's first collision
    boundary = ({"type": "dielectric", "int_ior": 1.33} if slab == "milk_in_glass"
                else {"type": "null"})
    d["slab"] = {"type": "cube", "to_world": box, "bsdf": boundary,
                 "interior": {"type": "ref", "id": "medium"}}
    return d


def render(slab: str, style: str, **kw) -> np.ndarray:
    return np.asarray(styletrace.render(scene(slab), style=style, **kw), dtype=np.float64)[..., :3]


def tone(image: np.ndarray, reference: np.ndarray, *rows: slice) -> float:
    pick = lambda a: np.concatenate([a[r] for r in rows])  # noqa: E731
    return measures.tone_correlation(pick(image), pick(reference), 8)


@pytest.fixture(scope="module")
def references():
    return {}


def reference(references: dict, slab: str) -> np.ndarray:
    if slab not in references:
        references[slab] = render(slab, "identity", spp=REF_SPP, seed=7)
    return references[slab]


@pytest.mark.parametrize("slab", ["glass", "milk_in_glass", "medium", "fog"])
@pytest.mark.parametrize("style", ["gamma", "hatching"])
def test_tone_through_glass_and_in_media_follows_the_direct_view(references, slab, style):
    """gamma (a curve at the auto exposure) and hatching (auto tones) at their defaults: over the
    direct rows and the slab's together the rank agreement is within MAX_LOSS of the direct rows'
    own."""
    ref = reference(references, slab)
    image = render(slab, style, seed=0)
    direct = tone(image, ref, DIRECT)
    both = tone(image, ref, DIRECT, SLAB)
    assert direct > 0.9, direct  # the style follows the plane seen directly
    assert both >= direct - MAX_LOSS, (direct, both)
