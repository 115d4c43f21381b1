"""Deep recursion at bounded cost: styletrace traces its kernels with Dr.Jit's OptimizeLoops off
(`integrator.tracing`), which leaves the images bit for bit as they were and makes the trace time
grow linearly with the stylized levels instead of doubling per level (issue 23, point 3)."""
import time

import numpy as np
import pytest

from styletrace.frontends import api
from styletrace.gate import dr, mi
from styletrace.kernel import integrator as I

#: traces per measurement; the least counts
REPEATS = 7


def trace_seconds(depth: int, style: str = "identity") -> float:
    """Wall time of tracing (recording, not compiling or running) the integrator's kernel at
    `depth` stylized levels, one child each: `sample` called on a few camera rays, its result
    dropped unevaluated. The least of REPEATS: tracing is deterministic work, so the minimum is
    the measurement with the least interference from other processes on the machine."""
    scene = api.load_scene("cornell-box", 4, 4)
    mode = dict(stylize="first_n_hits", stylize_depth=depth) if depth > 1 else {}
    integ = api.make_integrator(style, inner=1, **mode)
    sensor = scene.sensors()[0]
    best = float("inf")
    for _ in range(REPEATS):
        sampler = sensor.sampler().clone()
        sampler.seed(1, 16)
        ray, _ = sensor.sample_ray(
            mi.Float(0.0), mi.Float(0.5), sampler.next_2d(), sampler.next_2d()
        )
        t = time.perf_counter()
        out = integ.sample(scene, sampler, ray)
        best = min(best, time.perf_counter() - t)
        del out
    return best


def test_trace_time_grows_at_most_linearly_with_depth():
    """Depth 8 against depth 4: twice the levels. Linear growth gives a ratio of at most 2 (less
    with the fixed work outside the levels); with OptimizeLoops on, each level doubles the trace
    (the same test with `I.OPTIMIZE_LOOPS = True` fails: ratio 5.5 measured). The issue's
    explicit exception to 'no timings in tests'."""
    t4, t8 = trace_seconds(4), trace_seconds(8)
    assert t8 / t4 < 3.0, (
        f"trace time at depth 8 {t8:.3f} s, at depth 4 {t4:.3f} s: ratio {t8 / t4:.1f}"
    )


CONFIGS = {
    "cel first_hit": dict(scene="cornell-box", style="cel", inner=4),
    "saturation first_n_hits depth 2": dict(
        scene="cornell-box",
        style="saturation",
        inner=(2, 2),
        stylize="first_n_hits",
        stylize_depth=2,
    ),
    "gamma series (unbiased)": dict(
        scene="cornell-box", style="gamma", inner=4, estimator="series"
    ),
    "cel with lines": dict(scene="lines", style="cel", inner=2, lines=True),
}


@pytest.mark.parametrize("name", list(CONFIGS))
def test_images_are_bit_identical_with_optimize_loops_on_and_off(name, monkeypatch):
    cfg = dict(CONFIGS[name])
    scene = cfg.pop("scene")
    images = []
    for on in (True, False):
        monkeypatch.setattr(I, "OPTIMIZE_LOOPS", on)
        images.append(np.asarray(api.render(scene, spp=2, seed=3, width=8, height=8, **cfg)))
    assert np.array_equal(images[0].view(np.uint32), images[1].view(np.uint32)), \
        f"{name}: largest difference {np.abs(images[0] - images[1]).max():.3g}"


def test_the_flag_is_off_while_tracing_and_scoped(monkeypatch):
    """Off while the kernel's loops are recorded; a user's own Dr.Jit code keeps its setting (the
    default, on), before and after a render."""
    seen = []
    plain = I.StylizedIntegrator._sample

    def spy(self, *args, **kwargs):
        seen.append(dr.flag(dr.JitFlag.OptimizeLoops))
        return plain(self, *args, **kwargs)

    monkeypatch.setattr(I.StylizedIntegrator, "_sample", spy)
    before = dr.flag(dr.JitFlag.OptimizeLoops)
    api.render("cornell-box", style="cel", spp=1, inner=1, width=4, height=4)
    assert seen == [False]
    assert dr.flag(dr.JitFlag.OptimizeLoops) == before


def test_sixteen_levels_render():
    img = api.render(
        "cornell-box",
        style="saturation",
        spp=1,
        inner=1,
        stylize="first_n_hits",
        stylize_depth=16,
        width=4,
        height=4,
    )
    assert img.shape == (4, 4, 3) and np.isfinite(img).all()
