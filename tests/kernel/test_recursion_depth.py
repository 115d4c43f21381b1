"""Deep recursion at bounded cost: styletrace traces its kernels with Dr.Jit's OptimizeLoops off
(`integrator.tracing`), which leaves the images bit for bit as they were and makes the trace grow
linearly with the stylized levels instead of doubling per level (issue 23, point 3). The trace is
counted, not timed: how many times the path kernel below the last stylized level is traced
(`StylizedIntegrator._walk`), which OptimizeLoops multiplied by 2 per level (each loop's body
traced twice); its time is in BENCHMARKS.md (benchmarks/recursion_depth.py)."""
import numpy as np
import pytest

from styletrace.frontends import api
from styletrace.gate import dr, mi
from styletrace.kernel import integrator as I


def traced_walks(depth: int, monkeypatch, style: str = "identity") -> int:
    """How many times tracing the integrator's kernel at `depth` stylized levels, one child each,
    traces the path walk: `sample` called on a few camera rays, its result dropped unevaluated."""
    scene = api.load_scene("cornell-box", 4, 4)
    mode = dict(stylize="first_n_hits", stylize_depth=depth) if depth > 1 else {}
    integ = api.make_integrator(style, inner=1, **mode)
    calls, walk = [0], I.StylizedIntegrator._walk

    def counted(self, *args, **kw):
        calls[0] += 1
        return walk(self, *args, **kw)

    with monkeypatch.context() as m:
        m.setattr(I.StylizedIntegrator, "_walk", counted)
        sensor = scene.sensors()[0]
        sampler = sensor.sampler().clone()
        sampler.seed(1, 16)
        ray, _ = sensor.sample_ray(
            mi.Float(0.0), mi.Float(0.5), sampler.next_2d(), sampler.next_2d()
        )
        out = integ.sample(scene, sampler, ray)
        del out
    return calls[0]


def test_the_trace_grows_at_most_linearly_with_depth(monkeypatch):
    """Depth 8 against depth 4: twice the levels, at most twice the traced walks. With
    OptimizeLoops on, each level doubles them: 16 at depth 4, 256 at depth 8 (measured; the
    negative control below)."""
    w4, w8 = traced_walks(4, monkeypatch), traced_walks(8, monkeypatch)
    assert w8 <= 2 * w4, f"traced walks at depth 8: {w8}, at depth 4: {w4}"
    monkeypatch.setattr(I, "OPTIMIZE_LOOPS", True)  # the control: the doubling is seen
    assert traced_walks(8, monkeypatch) > 2 * traced_walks(4, monkeypatch)


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
