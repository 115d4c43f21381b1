"""Array backend: one small vocabulary over numpy and Dr.Jit.

The estimators are written once against these helpers and run unchanged on numpy arrays and on
Dr.Jit arrays inside a symbolic kernel. numpy sees per-lane scalars as (lanes, 1) and values as
(lanes, C), so broadcasting behaves like Dr.Jit's `Float * Array3f`; Dr.Jit per-lane scalars are the
value type's leaf Float. Dr.Jit is imported lazily and only if the caller already did.
`backend_module(like)` is the Dr.Jit array module to create arrays with; `numpy_while_loop` emulates
`drjit.while_loop`, compacting the active lanes. See docs/design/estimator_kernel_contract.md.
"""
from __future__ import annotations

import sys

import numpy as np

__all__ = [
    "is_drjit",
    "drjit",
    "backend_module",
    "select",
    "abs",
    "exp",
    "log",
    "sqrt",
    "cos",
    "sin",
    "minimum",
    "maximum",
    "clip",
    "hmax",
    "channel_mean",
    "tree_map",
    "tree_select",
    "numpy_while_loop",
    "const_like",
    "input_like",
]

_pyabs = abs


def drjit():
    """The drjit module if it has been imported by someone, else None (we never import it first)."""
    return sys.modules.get("drjit")


def _import_drjit():
    """drjit, imported through ``styletrace.jit.prepare_drjit`` (a working libLLVM) if nobody did
    yet."""
    dr = drjit()
    if dr is None:
        from styletrace.jit import prepare_drjit  # stdlib-only module: loads Dr.Jit, never Mitsuba
        prepare_drjit()
        import drjit as dr
    return dr


def _module_for(dr, backend, diff: bool):
    mod = dr.cuda if backend == dr.JitBackend.CUDA else dr.llvm
    return mod.ad if diff else mod


def backend_module(like=None):
    """The Dr.Jit array module to build arrays with (``drjit.llvm``, ``drjit.cuda``, or their .ad).

    Args:
        like: a Dr.Jit array type or instance (e.g. ``mitsuba.Color3f``): its backend and AD-ness.
            None: a loaded Mitsuba's cuda/llvm variant's (.ad for ``*_ad_*``), else drjit.cuda where
            CUDA works (``jit.prepare_drjit``) and ``drjit.llvm`` otherwise.

    Returns:
        The module; Dr.Jit imported if needed (with a working libLLVM), Mitsuba never.

    Raises:
        TypeError: ``like`` is not a CUDA or LLVM Dr.Jit array type.
    """
    dr = _import_drjit()
    if like is not None:
        tp = like if isinstance(like, type) else type(like)
        if (not issubclass(tp, dr.ArrayBase)
                or dr.backend_v(tp) not in (dr.JitBackend.CUDA, dr.JitBackend.LLVM)):
            raise TypeError(f"backend_module: {tp.__name__} is not a JIT (CUDA or LLVM) Dr.Jit "
                            "array type")
        return _module_for(dr, dr.backend_v(tp), bool(dr.is_diff_v(tp)))
    mi = sys.modules.get("mitsuba")
    variant = None
    if mi is not None:
        try:
            variant = mi.variant()
        except Exception:  # a half-imported Mitsuba: fall back to Dr.Jit's own view
            variant = None
    if variant and (variant.startswith("cuda") or variant.startswith("llvm")):
        backend = dr.JitBackend.CUDA if variant.startswith("cuda") else dr.JitBackend.LLVM
        return _module_for(dr, backend, "_ad_" in variant)
    from styletrace.jit import prepare_drjit
    cuda = prepare_drjit() == "cuda"
    return _module_for(dr, dr.JitBackend.CUDA if cuda else dr.JitBackend.LLVM, False)


def is_drjit(x) -> bool:
    """Whether x is a Dr.Jit array (False whenever Dr.Jit is not imported).

    Args:
        x: any value.

    Returns:
        True for an instance of ``drjit.ArrayBase``.
    """
    dr = drjit()
    return dr is not None and isinstance(x, dr.ArrayBase)


def _any_drjit(*xs) -> bool:
    return any(is_drjit(x) for x in xs)


def select(mask, a, b):
    """Elementwise ``a if mask else b``; a (lanes, 1) numpy mask broadcasts over channels.

    Args:
        mask: Dr.Jit Bool or numpy bool array; a, b: the values (Dr.Jit if any operand is).

    Returns:
        ``drjit.select`` or ``np.where`` of them.
    """
    if _any_drjit(mask, a, b):
        return drjit().select(mask, a, b)
    return np.where(mask, a, b)


def _unary(np_fn, dr_name):
    def fn(x):
        if is_drjit(x):
            return getattr(drjit(), dr_name)(x)
        return np_fn(x)
    fn.__name__ = dr_name
    return fn


abs = _unary(np.abs, "abs")  # noqa: A001  (mirrors numpy/drjit naming on purpose)
exp = _unary(np.exp, "exp")
log = _unary(np.log, "log")
sqrt = _unary(np.sqrt, "sqrt")
cos = _unary(np.cos, "cos")
sin = _unary(np.sin, "sin")


def minimum(a, b):
    """Elementwise minimum.

    Args:
        a, b: numpy arrays, Dr.Jit arrays or numbers (Dr.Jit if either is).

    Returns:
        ``drjit.minimum`` or ``np.minimum`` of them.
    """
    if _any_drjit(a, b):
        return drjit().minimum(a, b)
    return np.minimum(a, b)


def maximum(a, b):
    """Elementwise maximum.

    Args:
        a, b: numpy arrays, Dr.Jit arrays or numbers (Dr.Jit if either is).

    Returns:
        ``drjit.maximum`` or ``np.maximum`` of them.
    """
    if _any_drjit(a, b):
        return drjit().maximum(a, b)
    return np.maximum(a, b)


def clip(x, lo, hi):
    """Clamp x to [lo, hi].

    Args:
        x: the values (numpy or Dr.Jit).
        lo, hi: the bounds (numbers or arrays); None: unbounded on that side.

    Returns:
        The clamped values.
    """
    if lo is not None:
        x = maximum(x, lo)
    if hi is not None:
        x = minimum(x, hi)
    return x


def hmax(v):
    """Largest channel per lane: a per-lane scalar from a value (random decisions are per lane).

    Args:
        v: a Dr.Jit value (e.g. mi.Color3f) or numpy (lanes, C); other inputs are returned as is.

    Returns:
        Dr.Jit Float, or numpy (lanes, 1).
    """
    if is_drjit(v):
        dr = drjit()
        if dr.depth_v(v) > 1:
            out = v[0]
            for i in range(1, len(v)):
                out = dr.maximum(out, v[i])
            return out
        return v
    if isinstance(v, np.ndarray) and v.ndim >= 2:
        return v.max(axis=-1, keepdims=True)
    return v


def channel_mean(v):
    """Mean over the channels per lane, (r+g+b)/3 for RGB: a per-lane scalar from a value.

    Args:
        v: a Dr.Jit value (Color3f/Array3f) or numpy (lanes, C); other inputs are returned as is.

    Returns:
        Dr.Jit Float, or numpy (lanes, 1).
    """
    if is_drjit(v):
        dr = drjit()
        if dr.depth_v(v) > 1:
            out = v[0]
            for i in range(1, len(v)):
                out = out + v[i]
            return out * (1.0 / len(v))
        return v
    if isinstance(v, np.ndarray) and v.ndim >= 2:
        return v.mean(axis=-1, keepdims=True)
    return v


def const_like(c, x):
    """Constant c (scalar or one value per channel) in a form that combines elementwise with x.

    Args:
        c: a number, or a 1-D sequence with one value per channel of x.
        x: a value of the type to combine with (Dr.Jit array, or numpy with channels last).

    Returns:
        A float (scalar c), an instance of x's Dr.Jit type, or a numpy (C,) array of x's dtype.

    Raises:
        ValueError: c is not 0-D or 1-D, or its length is not x's channel count.
    """
    c = np.asarray(c, dtype=np.float64)
    if c.ndim == 0:
        return float(c)
    if c.ndim != 1:
        raise ValueError(f"a per-channel constant must be 1-D, got shape {c.shape}")
    if is_drjit(x):
        dr = drjit()
        n = dr.size_v(type(x)) if dr.depth_v(x) > 1 else 1
        if n != c.shape[0]:
            raise ValueError(f"{c.shape[0]} per-channel constants for a value of type "
                             f"{type(x).__name__} with {n} channel(s)")
        return type(x)(*[float(v) for v in c])
    x = np.asarray(x)
    if x.ndim == 0 or x.shape[-1] != c.shape[0]:
        raise ValueError(f"{c.shape[0]} per-channel constants for an array of shape {x.shape}: "
                         f"the last axis must hold the channels")
    return c.astype(x.dtype) if np.issubdtype(x.dtype, np.floating) else c


# ---------------------------------------------------------------------------------------------
# pytrees (tuple / list / dict) for loop states


def input_like(c: float, x):
    """The number `c` for arithmetic with `x`: as it is for numpy, and for a Dr.Jit `x` an opaque
    scalar of x's type, a kernel input rather than a literal (a new `c` reuses the kernel).

    Args:
        c: a Python number. x: a numpy or Dr.Jit value (its type for Dr.Jit).

    Returns:
        c, or a Dr.Jit array of width 1 holding it.
    """
    if not is_drjit(x):
        return c
    dr = drjit()
    return dr.opaque(dr.leaf_t(x) if dr.depth_v(x) > 1 else type(x), float(c))


def tree_map(fn, *trees):
    """Apply fn leafwise over pytrees of one structure (dicts, namedtuples, tuples, lists).

    Args:
        fn: called with the corresponding leaf of every tree.
        *trees: the pytrees; the first one's structure (dict keys) is followed.

    Returns:
        A pytree of that structure holding fn's results.
    """
    t0 = trees[0]
    if isinstance(t0, dict):
        return {k: tree_map(fn, *[t[k] for t in trees]) for k in t0}
    if isinstance(t0, tuple) and hasattr(t0, "_fields"):  # namedtuple
        return type(t0)(*[tree_map(fn, *xs) for xs in zip(*trees)])
    if isinstance(t0, (tuple, list)):
        return type(t0)(tree_map(fn, *xs) for xs in zip(*trees))
    return fn(*trees)


def tree_select(mask, a, b):
    """``select`` over two pytrees of the same structure; non-array leaves are taken from a.

    Args:
        mask: Dr.Jit Bool or numpy bool array, per lane.
        a, b: the pytrees chosen from where mask is true and false.

    Returns:
        The selected pytree.
    """
    def pick(x, y):
        if not (isinstance(x, np.ndarray) or isinstance(y, np.ndarray)
                or is_drjit(x) or is_drjit(y)):
            return x
        return select(mask, x, y)
    return tree_map(pick, a, b)


def _lane_leaf(x, lanes) -> bool:
    return isinstance(x, np.ndarray) and x.ndim >= 1 and x.shape[0] == lanes


def _take(tree, idx, lanes):
    return tree_map(lambda x: x[idx] if _lane_leaf(x, lanes) else x, tree)


def _put(old_tree, new_tree, idx, lanes):
    """Write the body's results for lanes idx back; per-lane leaves are updated in place when they
    can hold the result exactly (the loop owns them: ``numpy_while_loop`` copies the caller's arrays
    first)."""
    def put(old, new):
        if not isinstance(new, np.ndarray) and not isinstance(old, np.ndarray):
            return new  # shared leaf (generator, python constant): the body's version wins
        new = np.asarray(new)
        old = np.asarray(old)
        if not _lane_leaf(old, lanes) and not _lane_leaf(new, idx.size) and old.shape == new.shape \
                and np.array_equal(old, new):
            return old  # an unchanged broadcast literal stays a literal
        trail = np.broadcast_shapes(old.shape[1:] if old.ndim else (),
                                    new.shape[1:] if new.ndim else ())
        if (_lane_leaf(old, lanes) and old.shape[1:] == trail
                and np.can_cast(new.dtype, old.dtype, "safe")):
            if new is not old:
                old[idx] = np.broadcast_to(new, (idx.size,) + trail)
            return old
        out = np.array(np.broadcast_to(old, (lanes,) + trail), dtype=np.result_type(old, new))
        out[idx] = np.broadcast_to(new, (idx.size,) + trail)
        return out
    return tree_map(put, old_tree, new_tree)


def _flat_mask(mask):
    return mask.reshape(mask.shape[0], -1)[:, 0]


def numpy_while_loop(state: tuple, cond, body, set_lanes=None,
                     max_iterations: int = 10_000_000) -> tuple:
    """Masked, lane-compacting emulation of ``drjit.while_loop`` for numpy states.

    Args:
        state, cond, body: as drjit.while_loop's (a tuple of pytrees; cond(*state) -> a per-lane
            mask, 0-D: a plain loop; body(*state) -> state), called on the running lanes only.
        set_lanes: told the lanes cond and body see (k), then the full count; max_iterations: cap.

    Returns:
        The final state; a lane whose condition failed kept its state from then on.

    Raises:
        RuntimeError: lanes still run after max_iterations.
    """
    def call(fn, args, k, lanes):
        if set_lanes is not None:
            set_lanes(k)
        try:
            return fn(*args)
        finally:
            if set_lanes is not None:
                set_lanes(lanes)

    state = tuple(state)
    mask = np.asarray(cond(*state))
    if mask.ndim == 0:  # no per-lane data at all: a plain loop
        while mask:
            state = tuple(body(*state))
            mask = np.asarray(cond(*state))
        return state
    lanes = mask.shape[0]
    # own what we update
    state = tree_map(lambda x: np.array(x) if _lane_leaf(x, lanes) else x, state)
    running = np.flatnonzero(_flat_mask(mask))
    for _ in range(max_iterations):
        if running.size == 0:
            return state
        sub = state if running.size == lanes else _take(state, running, lanes)
        new = tuple(call(body, sub, running.size, lanes))
        state = _put(state, new, running, lanes)
        sub = state if running.size == lanes else _take(state, running, lanes)
        running = running[_flat_mask(np.asarray(call(cond, sub, running.size, lanes)))]
    raise RuntimeError(f"numpy_while_loop: no termination after {max_iterations} iterations")
