"""Lifetimes of scenes and of the scene-defaults pilot around a render.

A scene that Python's cyclic collector finalised while a pass was being recorded made LLVM abort
("invalid redefinition of function"); passes are now recorded and launched with the automatic
collector paused (jit.no_collection), so no render needs a collection of its own. Recording a
look-dev buffer traces the scene-defaults pilot once: the auto values and the buffer share it.
"""
import functools
import gc
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from conftest import child_env

from styletrace.frontends import api
from styletrace.frontends.cli import main
from styletrace.gate import mi
from styletrace.kernel import reuse
from styletrace.lookdev.record import record
from styletrace.pipeline.passes import Shot
from styletrace.scene import defaults as scene_defaults

from .test_reuse import plane_scene

TESTS = Path(__file__).resolve().parents[1]

#: In a child process (an abort ends it): render the glowing shell once while a scene with a mask
#: BSDF is alive, then render it again and, at the N-th walk traced, turn the mask scene into young
#: cyclic garbage and lower the collector's threshold to 1, so that an automatic collection (not an
#: explicit one, which any pause would let through) comes at the next allocation, inside the
#: recording of the pass. Measured before the pause: both modes aborted ("invalid redefinition of
#: function"), reuse at N = 1..4, the tree (api.passes) at N = 3 while OptimizeLoops traced each
#: loop body twice, at N = 1 since it is off while tracing (the tree traces one walk per render now;
#: all three cases abort without the pause, measured).
CHILD = r"""
import gc, sys
import styletrace; styletrace.init()
import mitsuba as mi, numpy as np
from styletrace.frontends import api
from styletrace.kernel import integrator as integrator_module, reuse
from kernel.test_reuse import plane_scene
from kernel.test_reuse_depth2 import shell_scene

mode, n = sys.argv[1], int(sys.argv[2])
d = plane_scene(8)
d["plane"]["bsdf"] = {"type": "mask", "opacity": 0.5, "material": d["plane"]["bsdf"]}
holder = [mi.load_dict(d)]
shell = mi.load_dict(shell_scene())
if mode == "reuse":
    integ = api.make_integrator("identity", inner=2, stylize="first_n_hits", stylize_depth=2,
                                reuse="pixels", reuse_k=12)
    render = lambda seed: reuse.render_reuse(integ, shell, shell.sensors()[0], seed, 8)
else:
    integ = api.make_integrator("identity", inner=2, stylize="first_n_hits", stylize_depth=2)
    render = lambda seed: next(iter(api.passes(shell, integ, 4, seed))).image
render(1)
walk, calls = integrator_module.walk, [0]

def walk_that_drops_the_scene(*args, **kw):
    calls[0] += 1
    if calls[0] == n:
        cycle = {"scene": holder.pop()}
        cycle["self"] = cycle
        del cycle
        gc.set_threshold(1)
    return walk(*args, **kw)

integrator_module.walk = walk_that_drops_the_scene
image = np.asarray(render(2), dtype=np.float64)[..., :3]
assert calls[0] >= n and not holder, calls
print("mean", image.mean())
"""


@pytest.mark.parametrize("mode,n", [("reuse", 1), ("reuse", 3), ("passes", 1)])
def test_a_scene_collected_during_a_trace_does_not_abort_the_render(mode, n, tmp_path):
    env = child_env()
    # the child imports the scenes of kernel.test_reuse*
    env["PYTHONPATH"] += os.pathsep + str(TESTS)
    r = subprocess.run(
        [sys.executable, "-c", CHILD, mode, str(n)],
        capture_output=True,
        text=True,
        timeout=600,
        env=env,
    )
    assert r.returncode == 0, r.stderr[-2000:]
    # the identity style inside a shell of radiance 1 and albedo 0.5 sees 2 on average
    # (test_reuse_depth2); 4 to 8 samples per pixel on 24 x 24 pixels: the mean is within a few
    # percent
    assert abs(float(r.stdout.split()[-1]) - 2.0) < 0.2, r.stdout


def test_reuse_render_collects_no_garbage_and_leaves_the_collector_as_it_was(monkeypatch):
    """The per-render gc.collect (35 ms, a third of a 128 x 128 reuse render) is gone: the pause
    makes it unneeded. The collector is enabled after the render exactly when it was before."""
    calls = []
    monkeypatch.setattr(gc, "collect", lambda *a: calls.append(a) or 0)
    scene = mi.load_dict(plane_scene(8))
    integ = api.make_integrator("identity", inner=2, reuse="pixels", reuse_k=4)
    for enabled in (True, False):
        (gc.enable if enabled else gc.disable)()
        try:
            for seed in range(2):
                reuse.render_reuse(
                    integ,
                    mi.load_dict(plane_scene(8)) if seed else scene,
                    scene.sensors()[0],
                    seed,
                    1,
                )
            assert gc.isenabled() == enabled
        finally:
            gc.enable()
    assert calls == []


@pytest.fixture
def counted_pilot(monkeypatch):
    """How often the scene-defaults pilot is traced (its `records`, a cached property, computed)."""
    traces = []
    original = scene_defaults.ScenePilot.__dict__["records"].func

    @functools.wraps(original)
    def records(self):
        traces.append(self)
        return original(self)

    prop = functools.cached_property(records)
    prop.__set_name__(scene_defaults.ScenePilot, "records")
    monkeypatch.setattr(scene_defaults.ScenePilot, "records", prop)
    return traces


SCENE = """<scene version="3.0.0"><sensor type="perspective"><film type="hdrfilm"><integer \
name="width" value="6"/>
<integer name="height" value="4"/><rfilter type="box"/></film></sensor><shape \
type="sphere"/><emitter type="constant"/></scene>"""


def test_recording_a_buffer_from_the_command_line_traces_the_pilot_once(
    tmp_path, counted_pilot, capsys
):
    """cel's thresholds are auto values (a pilot is needed) and the buffer stores the pilot: once
    for both."""
    (tmp_path / "s.xml").write_text(SCENE)
    assert main(["render", str(tmp_path / "s.xml"), "--style", "cel", "--spp", "2", "--buffer",
                 str(tmp_path / "b.npz"), "-o", str(tmp_path / "x.exr")]) == 0
    assert "auto values: cel thresholds=" in capsys.readouterr().err
    assert len(counted_pilot) == 1


def test_recording_a_buffer_through_the_api_traces_the_pilot_once(tmp_path, counted_pilot):
    scene = api.load_scene(str((tmp_path / "s.xml").write_text(SCENE) and tmp_path / "s.xml"))
    for _, buf in record(Shot(scene, api.make_integrator("cel"), 2)):
        pass
    assert len(counted_pilot) == 1
    # the pilot's samples are in the buffer
    assert np.count_nonzero(buf.arrays["pilot_owner"] >= 0) > 0
