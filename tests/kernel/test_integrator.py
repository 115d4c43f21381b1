"""The `stylized` integrator object itself: what it keeps between renders."""
import os
import subprocess
import sys

from conftest import child_env

TESTS = os.path.abspath(os.path.join(os.path.dirname(__file__), ".."))

SCENARIO = """
import gc, sys
sys.path[:0] = [{tests!r}, {render!r}]
import styletrace
from styletrace.frontends.api import make_integrator, passes
from test_recursion import sky_scene
kept = []


def check(depth):
    integ = make_integrator("identity", stylize="first_object_hit", stylize_depth=depth)
    for k in range(3):
        list(passes(sky_scene(24, styled=True), integ, 8, seed=k))
    raise AssertionError("a failed check: its frame keeps the integrator alive")


for depth in (1, 2):
    try:
        check(depth)
    except AssertionError as exc:
        kept.append(exc)
    gc.collect()  # tears down the first scenes' reference cycles while their integrator lives on
print("survived")
"""


def test_no_scene_objects_outlive_the_trace():
    """An integrator kept alive after its scene is collected must not make the next trace crash
    (it did: Dr.Jit traces calls on every live emitter, and one of a half-collected scene
    segfaulted)."""
    code = SCENARIO.format(tests=TESTS, render=os.path.join(TESTS, "kernel"))
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=300,
                       env=child_env())
    assert r.returncode == 0 and "survived" in r.stdout, (r.returncode, r.stderr[-2000:])
