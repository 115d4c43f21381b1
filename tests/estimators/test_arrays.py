"""The numpy / Dr.Jit backend helpers and the numpy emulation of drjit.while_loop."""
import numpy as np
import pytest

from styletrace.estimators import arrays as A


def test_select_broadcasts_a_lane_mask_over_channels():
    m = np.array([[True], [False]])
    out = A.select(m, np.ones((2, 3)), np.zeros((2, 3)))
    np.testing.assert_array_equal(out, [[1, 1, 1], [0, 0, 0]])


def test_hmax_and_const_like_on_both_backends(jit):
    Array3f, Float = jit.Array3f, jit.Float
    v = np.array([[1.0, 5.0, 2.0], [0.0, -1.0, 3.0]])
    np.testing.assert_array_equal(A.hmax(v), [[5.0], [3.0]])
    d = Array3f(Float([1, 0]), Float([5, -1]), Float([2, 3]))
    np.testing.assert_array_equal(np.asarray(A.hmax(d)), [5, 3])
    c = A.const_like([1.0, 2.0, 3.0], d)
    assert isinstance(c, Array3f)
    with pytest.raises(
        ValueError, match="3 per-channel constants for a value of type Float with 1 channel"
    ):
        A.const_like([1.0, 2.0, 3.0], Float(1.0))
    with pytest.raises(ValueError, match="last axis must hold the channels"):
        A.const_like([1.0, 2.0], np.ones((4, 3)))


def test_numpy_while_loop_runs_each_lane_its_own_number_of_times():
    limit = np.array([0, 3, 1, 5])
    rng = np.random.default_rng(0)
    seen = []

    def cond(i, lim, gen, log):
        return i < lim

    def body(i, lim, gen, log):
        seen.append(len(i))  # the body only sees the running lanes
        return i + 1, lim, gen, log + 1

    caller_counter = np.zeros(4, np.int64)
    i, lim, gen, log = A.numpy_while_loop(
        (np.zeros(4, np.int64), limit, rng, caller_counter), cond, body
    )
    np.testing.assert_array_equal(i, limit)
    np.testing.assert_array_equal(log, limit)
    assert gen is rng and seen == [3, 2, 2, 1, 1]
    # the loop updates its own copies in place, never the caller's
    assert np.all(caller_counter == 0)


def test_numpy_while_loop_reports_the_lane_count_to_fresh_allocations():
    sizes = []

    def cond(i, lim):
        return i < lim

    def body(i, lim):
        sizes.append(i.shape[0])
        return i + 1, lim

    A.numpy_while_loop(
        (np.zeros(3, np.int64), np.array([2, 0, 1])), cond, body, set_lanes=sizes.append
    )
    # set_lanes(k) before each call with k lanes, then the full count again
    assert sizes[:3] == [2, 2, 3]


def test_tree_select_and_map_follow_dicts_and_tuples():
    a = {"x": np.array([1.0, 2.0]), "t": (np.array([1, 1]), "keep")}
    b = {"x": np.array([5.0, 6.0]), "t": (np.array([0, 0]), "other")}
    out = A.tree_select(np.array([True, False]), a, b)
    np.testing.assert_array_equal(out["x"], [1.0, 6.0])
    np.testing.assert_array_equal(out["t"][0], [1, 0])
    assert out["t"][1] == "keep"


def test_math_helpers_dispatch(jit):
    Float = jit.Float
    x = np.array([0.25, 1.0])
    for fn, ref in (
        (A.exp, np.exp),
        (A.log, np.log),
        (A.sqrt, np.sqrt),
        (A.cos, np.cos),
        (A.abs, np.abs),
    ):
        np.testing.assert_allclose(fn(x), ref(x))
        np.testing.assert_allclose(np.asarray(fn(Float(x))), ref(x), rtol=1e-6)
    np.testing.assert_array_equal(A.clip(np.array([-1.0, 0.5, 9.0]), 0.0, 1.0), [0.0, 0.5, 1.0])
    assert A.clip(np.array([3.0]), None, None)[0] == 3.0


def test_backend_module_follows_like_then_the_mitsuba_variant_then_cuda(jit, monkeypatch):
    import sys
    import types

    import drjit as dr
    assert A.backend_module(jit.Float) is jit and A.backend_module(jit.Array3f(1, 2, 3)) is jit
    # explicitly about backends: like decides, whatever is in use (types of any JIT backend exist
    # everywhere)
    assert (
        A.backend_module(dr.cuda.ad.Array3f) is dr.cuda.ad
        and A.backend_module(dr.llvm.Float) is dr.llvm
    )
    with pytest.raises(TypeError, match="not a JIT"):
        A.backend_module(dr.scalar.Array3f)
    # no like: an active Mitsuba variant decides (a stand-in module: the estimators never import
    # mitsuba)
    for variant, expected in (
        ("cuda_ad_rgb", dr.cuda.ad),
        ("llvm_ad_rgb", dr.llvm.ad),
        ("llvm_rgb", dr.llvm),
    ):
        monkeypatch.setitem(
            sys.modules, "mitsuba", types.SimpleNamespace(variant=lambda v=variant: v)
        )
        assert A.backend_module() is expected, variant
    # no variant set: CUDA where it works (the package's own test, which honours
    # STYLETRACE_NO_CUDA), else LLVM
    from styletrace import jit as backend_choice
    monkeypatch.setitem(sys.modules, "mitsuba", types.SimpleNamespace(variant=lambda: None))
    assert A.backend_module() is (dr.cuda if backend_choice.cuda_usable() else dr.llvm)
    monkeypatch.setattr(backend_choice, "cuda_usable", lambda: True)
    assert A.backend_module() is dr.cuda
    monkeypatch.setattr(backend_choice, "cuda_usable", lambda: False)
    assert A.backend_module() is dr.llvm
