"""The `owen_sobol` sampler (kernel/owen_sobol_sampler.py) in renders: unbiased under Mitsuba's
`path` and the `stylized` integrator, one sequence across passes, and lower error than the
`independent` sampler at equal samples on scenes it was not tuned on."""
import numpy as np
import pytest

from styletrace.errors import SceneError
from styletrace.frontends import api
from styletrace.gate import mi
from styletrace.kernel.owen_sobol_sampler import OwenSobolSampler
from styletrace.pipeline import passes as pass_loop
from styletrace.scene.loading import scene_dict

RES = 32
#: renders per sampler, and their camera samples per pixel
SEEDS, SPP = 16, 16
#: a block's |t| bound with SEEDS - 1 = 15 degrees of freedom: P(|t| > 5) = 1.6e-4, so 48 block
#: channels all pass with probability 0.99 for an unbiased renderer
ZT = 5.0


def scene(name: str, sampler: str, res: int = RES) -> mi.Scene:
    return api.load_scene(name, res, res, sampler=sampler)


def render(sc, integrator, spp: int, seed: int) -> np.ndarray:
    return list(api.passes(sc, integrator, spp, seed=seed))[-1].image[..., :3].astype(np.float64)


def block_means(img: np.ndarray, b: int = 8) -> np.ndarray:
    h, w = img.shape[:2]
    return img.reshape(h // b, b, w // b, b, 3).mean(axis=(1, 3))


def test_the_built_in_scenes_use_it():
    for name in ("cornell-box", "dragon", "mixed", "lines", "furnace"):
        assert isinstance(api.load_scene(name, 8, 8).sensors()[0].sampler(), OwenSobolSampler)


def test_mitsubas_path_is_unbiased_with_it():
    """Mitsuba's own `path` draws from it like any sampler (its loop carries the lanes' state):
    the Cornell box's 8 x 8 block means agree with `independent`'s, each side's variance from
    the spread of SEEDS renders (|t| < ZT)."""
    path = mi.load_dict({"type": "path", "max_depth": 6})
    sides = []
    for sampler in ("owen_sobol", "independent"):
        sc = scene("cornell-box", sampler)
        blocks = np.stack([block_means(np.asarray(mi.render(sc, integrator=path, spp=SPP,
                                                             seed=s), np.float64))
                           for s in range(SEEDS)])
        sides.append((blocks.mean(axis=0), blocks.var(axis=0, ddof=1) / SEEDS))
    (m1, v1), (m2, v2) = sides
    z = (m1 - m2) / np.sqrt(v1 + v2 + 1e-12)
    assert np.abs(z).max() < ZT, np.abs(z).max()


@pytest.mark.parametrize("name", ["cornell-box", "dragon"])
def test_identity_matches_path_and_is_closer_at_equal_samples(name):
    """The stylized identity with `owen_sobol` against Mitsuba's `path` (independent, 2 x 2048
    spp): every 8 x 8 block within ZT of its standard errors (the variance of the mean of SEEDS
    renders from their spread, a t statistic with SEEDS - 1 degrees of freedom, plus the
    reference's), and the mean squared error at SPP samples per pixel at most half of
    `independent`'s with the same integrator and seeds. Measured when written: 0.15 of it on the
    Cornell box, 0.29 on the dragon."""
    identity = api.make_integrator_from(dict(style="identity", inner_samples=1))
    ref_sc = scene(name, "independent")
    path = mi.load_dict({"type": "path"})
    refs = [np.asarray(mi.render(ref_sc, integrator=path, spp=2048, seed=100 + s), np.float64)
            for s in range(2)]
    ref = (refs[0] + refs[1]) / 2
    # a block mean's variance: the pixels' (of the mean of two: ((r1 - r2) / 2)^2) over 64
    ref_var = block_means(((refs[0] - refs[1]) / 2) ** 2) / 64
    errors = {}
    for sampler in ("owen_sobol", "independent"):
        sc = scene(name, sampler)
        imgs = [render(sc, identity, SPP, s) for s in range(SEEDS)]
        errors[sampler] = np.mean([((i - ref) ** 2).mean() for i in imgs])
        if sampler == "owen_sobol":
            blocks = np.stack([block_means(i) for i in imgs])
            var = blocks.var(axis=0, ddof=1) / SEEDS + ref_var
            z = (blocks.mean(axis=0) - block_means(ref)) / np.sqrt(var + 1e-12)
            assert np.abs(z).max() < ZT, np.abs(z).max()
    assert errors["owen_sobol"] < 0.5 * errors["independent"], errors


def test_passes_continue_one_sequence():
    """64 samples per pixel in passes of 1, 4 or all at once: the same samples (the same image to
    float rounding). Without the pass loop's place in the sequence each pass would be a sequence
    of its own, and the images differ."""
    sc = scene("cornell-box", "owen_sobol")
    identity = api.make_integrator_from(dict(style="identity", inner_samples=1))
    images = [list(api.passes(sc, identity, 64, seed=3, pass_spp=p))[-1].image
              for p in (None, 1, 4)]
    assert np.allclose(images[0], images[1], atol=1e-5)
    assert np.allclose(images[0], images[2], atol=1e-5)


def test_without_the_sequence_passes_differ(monkeypatch):
    sc = scene("cornell-box", "owen_sobol")
    identity = api.make_integrator_from(dict(style="identity", inner_samples=1))
    whole = list(api.passes(sc, identity, 16, seed=3))[-1].image
    monkeypatch.setattr(pass_loop, "unit_sequence", lambda seed, unit: None)
    split = list(api.passes(sc, identity, 16, seed=3, pass_spp=4))[-1].image
    assert not np.allclose(whole, split, atol=1e-3)


def test_a_bad_sampler_is_refused_in_one_line():
    with pytest.raises(SceneError, match=r"bad sampler 'sobol'.*owen_sobol, independent"):
        scene_dict("cornell-box", 8, 8, sampler="sobol")
    with pytest.raises(SceneError, match="built-in scenes only"):
        api.load_scene(scene_dict("cornell-box", 8, 8), sampler="independent")
