"""The estimator protocol and the kernel driver that every estimator shares.

`Estimator` is a per-lane state machine fed one input sample at a time: `start(ctx, carry)`,
`wants(ctx, state)` (lanes that need another sample), `feed(ctx, state, x, mask, carry)`,
`value(ctx, state)` and `next_u(ctx, state)` (the stratified first dimension of the next draw, or
None). `Estimator.run` is the kernel contract of the package docstring: one loop, one `draw` per
iteration and lane. The `Context` hides the backend: per-lane constants, tables, uniforms and the
while loop. See docs/design/estimator_kernel_contract.md.
"""
from __future__ import annotations

import numpy as np

from styletrace.estimators import arrays as A

__all__ = ["Context", "Estimator", "check_count", "register_combinator", "combinator"]

#: Composite estimators behind the operator sugar (``a + b``, ``a * b``), keyed "sum" / "product".
#: ``algebra.py`` fills this in when it is imported (the package ``__init__`` always imports it), so
#: that this module needs neither ``algebra`` nor ``affine`` (which both build on it).
_COMBINATORS: dict = {}


def register_combinator(name: str, cls) -> None:
    """Make ``cls(a, b)`` the estimator that operator ``name`` builds.

    Args:
        name: "sum" (``a + b``) or "product" (``a * b``).
        cls: the estimator class, called with the two operands.
    """
    _COMBINATORS[name] = cls


def combinator(name: str):
    """The estimator class registered for operator ``name`` (see ``register_combinator``).

    Args:
        name: "sum" or "product".

    Returns:
        The class.

    Raises:
        RuntimeError: none registered (styletrace.estimators, which imports algebra, not imported).
    """
    try:
        return _COMBINATORS[name]
    except KeyError:
        raise RuntimeError(f"no {name!r} combinator registered: import styletrace.estimators "
                           f"(its algebra module provides them)") from None


def check_count(name: str, value, minimum: int = 1) -> int:
    """An integer parameter >= minimum, or a ValueError naming it.

    Args:
        name: the parameter's name, for the message.
        value: the value (a Python or numpy integer; bool is refused).
        minimum: the smallest allowed value.

    Returns:
        The value as an int.

    Raises:
        ValueError: not an integer, or below minimum.
    """
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < minimum:
        raise ValueError(f"{name} must be an integer >= {minimum}, got {value!r}")
    return int(value)


class Context:
    """Backend-specific helpers for one ``run`` (numpy lanes or a Dr.Jit value type); made by
    ``for_run``.

    Args:
        backend: "numpy" or "drjit".
        lanes: numpy: the lane count (``while_loop`` narrows it to the running lanes).
        like_t: Dr.Jit: the value type (e.g. mi.Color3f); float_t, uint_t, bool_t derive from it.
        dtype, channels, ndim: numpy: the samples' dtype, channel count C and ndim (1 or 2); None
            until known (``adopt`` fills them from the first sample).
        uniform: the caller's uniform(carry) -> (u, carry).
    """

    def __init__(
        self,
        backend: str,
        *,
        lanes=None,
        like_t=None,
        dtype=None,
        channels=None,
        ndim=None,
        uniform=None,
    ):
        self.backend = backend
        self.lanes = lanes
        self.like_t = like_t
        self.dtype = dtype
        self.channels = channels
        self.ndim = ndim
        self._uniform = uniform
        self._tables = {}
        if backend == "drjit":
            dr = A.drjit()
            self.float_t = dr.leaf_t(like_t)
            self.uint_t = dr.uint32_array_t(self.float_t)
            self.bool_t = dr.mask_t(self.float_t)

    # -- construction ------------------------------------------------------------------------
    @classmethod
    def for_run(cls, like, active, uniform, carry):
        """Pick the backend from `like` / `active`; numpy may probe `uniform` for the lane count.

        Args:
            like, active, uniform, carry: as ``Estimator.run`` takes them.

        Returns:
            (ctx, carry): the context, and carry (advanced where uniform was probed).

        Raises:
            ValueError: like is neither a Dr.Jit type nor a numpy array of shape (lanes,) or
                (lanes, C); Dr.Jit `active` or uniforms without like; lane counts that disagree.
        """
        dr = A.drjit()
        like_t = like if isinstance(like, type) else (type(like) if like is not None else None)
        if like_t is not None and dr is not None and issubclass(like_t, dr.ArrayBase):
            return cls("drjit", like_t=like_t, uniform=uniform), carry
        if like is not None and not isinstance(like, np.ndarray):
            raise ValueError(
                "like must be the type (or an instance) of the samples draw() returns: a Dr.Jit "
                "array type such as mitsuba.Color3f, or a numpy array of shape (lanes,) / (lanes, "
                f"C); got {like!r}"
            )
        if A.is_drjit(active):
            raise ValueError("the Dr.Jit backend needs like=<type of the samples draw() returns>, "
                             "e.g. like=mitsuba.Color3f or like=drjit.llvm.Float")
        lanes = dtype = channels = ndim = None
        if like is not None:
            arr = like
            if arr.ndim not in (1, 2):
                raise ValueError(f"like must have shape (lanes,) or (lanes, C), got {arr.shape}")
            lanes, dtype, ndim = arr.shape[0], arr.dtype, arr.ndim
            channels = arr.shape[1] if arr.ndim == 2 else 1
        if active is not None:
            active = np.asarray(active)
            if lanes is not None and active.shape[0] != lanes:
                raise ValueError(f"active has {active.shape[0]} lanes but like has {lanes}")
            lanes = active.shape[0]
        if lanes is None:  # nothing says how many lanes: ask the random stream
            u, carry = uniform(carry)
            if A.is_drjit(u):
                raise ValueError("the Dr.Jit backend needs like=<type of the samples draw() "
                                 "returns>")
            lanes = np.asarray(u).shape[0]
        return cls("numpy", lanes=lanes, dtype=dtype, channels=channels, ndim=ndim,
                   uniform=uniform), carry

    @property
    def is_drjit(self) -> bool:
        return self.backend == "drjit"

    # -- per-lane scalars, masks, values -------------------------------------------------------
    def lane(self, v: float):
        """A per-lane scalar holding v.

        Args:
            v: the number.

        Returns:
            The Dr.Jit leaf Float, or numpy (lanes, 1).
        """
        if self.is_drjit:
            return self.float_t(float(v))
        return np.full((self.lanes, 1), float(v))

    def mask(self, v: bool):
        """A per-lane mask holding v.

        Args:
            v: the bool.

        Returns:
            The Dr.Jit Bool of the value type, or numpy bool (lanes, 1).
        """
        if self.is_drjit:
            return self.bool_t(bool(v))
        return np.full((self.lanes, 1), bool(v))

    def vzero(self):
        if self.is_drjit:
            return self.like_t(0.0)
        return np.zeros((self.lanes, 1))

    def vconst(self, c):
        """c (scalar or per-channel) as something that combines with values.

        Args:
            c: a number, or one per channel (numpy: sets the channel count if none is known yet).

        Returns:
            A float, a value of like_t, or a numpy (C,) array (``arrays.const_like``).

        Raises:
            ValueError: c's shape, or its channel count, does not fit the values.
        """
        c = np.asarray(c, dtype=np.float64)
        # scalars, bad shapes and Dr.Jit values: const_like's checks
        if self.is_drjit or c.ndim != 1:
            return A.const_like(c, self.like_t(0.0) if self.is_drjit
                                else np.zeros(c.shape[-1:] or (1,)))
        if self.channels is not None and self.channels != c.shape[0]:
            raise ValueError(f"{c.shape[0]} per-channel constants for samples with {self.channels} "
                             "channel(s)")
        self.channels = c.shape[0]
        return c

    def value_array(self, c):
        """A per-lane value holding constant c (state entries must be arrays, never Python
        floats).

        Args:
            c: a number, or one per channel (as ``vconst``).

        Returns:
            A like_t value, or numpy (lanes, C).
        """
        return self.vzero() + self.vconst(c)

    # -- randomness and samples -----------------------------------------------------------------
    def uniform(self, carry):
        """One uniform per lane from the caller's stream.

        Args:
            carry: the caller's pytree, handed to its uniform(carry).

        Returns:
            (u, carry): u a Dr.Jit Float, or numpy float64 (lanes, 1).
        """
        u, carry = self._uniform(carry)
        if not self.is_drjit:
            u = np.asarray(u, dtype=np.float64).reshape(-1, 1)
        return u, carry

    def adopt(self, x):
        """A sample from draw() in the estimators' layout, checked against what we expect.

        Args:
            x: what draw() returned: a Dr.Jit array, or numpy (lanes,) or (lanes, C).

        Returns:
            x as like_t, or numpy (lanes, C) (the first sample fixes ndim, dtype, channels).

        Raises:
            ValueError: not a Dr.Jit array where one was promised, a bad shape, or a channel count
                other than the one expected.
        """
        if self.is_drjit:
            if not A.is_drjit(x):
                raise ValueError(f"draw() returned {type(x).__name__}; like={self.like_t.__name__} "
                                 "promised a Dr.Jit array")
            if type(x) is not self.like_t:
                x = self.like_t(x)
            return x
        x = np.asarray(x)
        if x.ndim not in (1, 2):
            raise ValueError(f"draw() must return shape (lanes,) or (lanes, C), got {x.shape}")
        channels = x.shape[1] if x.ndim == 2 else 1
        if self.ndim is None:
            self.ndim, self.dtype = x.ndim, x.dtype
        if self.channels is None:
            self.channels = channels
        elif self.channels != channels:
            raise ValueError(
                f"draw() returned {channels} channel(s) where {self.channels} were expected "
                f"(per-channel coefficients or like= say so)"
            )
        return x.reshape(x.shape[0], -1)

    def user_u(self, u):
        """The comb's first-dimension uniform in the layout draw() receives.

        Args:
            u: the per-lane uniform (Dr.Jit Float or numpy (lanes, 1)).

        Returns:
            u as it is (Dr.Jit), or flattened to numpy (lanes,).
        """
        return u if self.is_drjit else np.asarray(u).reshape(-1)

    # -- tables indexed per lane --------------------------------------------------------------
    def _table(self, table):
        key = id(table)
        if key not in self._tables:
            self._tables[key] = (table, self.float_t(np.asarray(table, dtype=np.float64)))
        return self._tables[key][1]

    def lookup(self, table: np.ndarray, k):
        """table[k] per lane.

        Args:
            table: a 1-D table of floats.
            k: per-lane integer-valued floats, clamped into [0, len(table) - 1].

        Returns:
            The entries, a Dr.Jit Float (gathered) or numpy float64 of k's shape.
        """
        n = len(table)
        if self.is_drjit:
            dr = A.drjit()
            idx = self.uint_t(dr.clip(k, 0, n - 1))
            return dr.gather(self.float_t, self._table(table), idx)
        idx = np.clip(np.asarray(k), 0, n - 1).astype(np.int64)
        return np.asarray(table, dtype=np.float64)[idx]

    def count_above(self, survival: np.ndarray, u):
        """#{k >= 1 : survival[k] > u} for a non-increasing table with survival[0] = 1 > u, by a
        binary search with a fixed number of steps (the traced kernel has no data-dependent loop).

        Args:
            survival: the non-increasing table, survival[0] = 1.
            u: per-lane uniforms in [0, 1).

        Returns:
            The count per lane, as an integer-valued per-lane float.
        """
        K = len(survival) - 1
        lo = self.lane(0.0)            # survival[lo] > u holds
        hi = self.lane(float(K + 1))   # first index known to fail (K + 1: past the table)
        for _ in range(int(np.ceil(np.log2(K + 1))) + 1):
            mid = self._floor((lo + hi) * 0.5)  # == lo once converged, which keeps lo
            ok = self.lookup(survival, mid) > u
            lo = A.select(ok, mid, lo)
            hi = A.select(ok, hi, mid)
        return lo

    def _floor(self, x):
        if self.is_drjit:
            return A.drjit().floor(x)
        return np.floor(x)

    def when(self, mask, compute, otherwise):
        """select(mask, compute(), otherwise), skipping the computation on numpy when no lane needs
        it (a traced Dr.Jit kernel evaluates both sides anyway; numpy saves expensive work, like
        re-expanding a polynomial about a pilot b, on iterations where no lane finished).

        Args:
            mask: per-lane mask; compute: () -> a pytree like `otherwise`; otherwise: a pytree.

        Returns:
            ``arrays.tree_select(mask, compute(), otherwise)``, or `otherwise` itself.
        """
        if not self.is_drjit and not np.any(mask):
            return otherwise
        return A.tree_select(mask, compute(), otherwise)

    # -- loops ----------------------------------------------------------------------------------
    def while_loop(self, state: tuple, cond, body) -> tuple:
        """``drjit.while_loop``, or its numpy emulation (``lanes`` follows the running lanes).

        Args:
            state: a tuple of pytrees.
            cond: cond(*state) -> per-lane mask; body: body(*state) -> the new state.

        Returns:
            The final state, as a tuple.
        """
        if self.is_drjit:
            return tuple(A.drjit().while_loop(state=tuple(state), cond=cond, body=body))
        def set_lanes(k):
            self.lanes = k
        return A.numpy_while_loop(tuple(state), cond, body, set_lanes)

    def finish(self, value, active):
        """The estimate in the caller's layout: inactive lanes 0, numpy reshaped and cast back.

        Args:
            value: the estimator's value (like_t, or numpy (lanes, C) or broadcastable to it).
            active: the caller's active lanes, or None for all.

        Returns:
            A like_t value, or numpy in the samples' shape ((lanes,) or (lanes, C)) and dtype.
        """
        if self.is_drjit:
            if not isinstance(value, self.like_t):
                value = self.like_t(value)
            if active is not None:
                value = A.drjit().select(active, value, self.like_t(0.0))
            return value
        value = np.asarray(value, dtype=np.float64)
        value = np.broadcast_to(value, (self.lanes, value.shape[1] if value.ndim == 2 else 1))
        if self.channels is not None and value.shape[1] != self.channels:
            value = np.broadcast_to(value, (self.lanes, self.channels))
        if active is not None:
            value = np.where(np.asarray(active).reshape(-1, 1), value, 0.0)
        if self.ndim == 1 or (self.ndim is None and value.shape[1] == 1):
            value = value[:, 0]
        return np.array(value, dtype=self.dtype if self.dtype is not None else np.float64)


class Estimator:
    """Base class: a group-unbiased (or, for ``Direct``, consistent) estimator of g(I)."""

    name = "estimator"

    # -- protocol (overridden) ------------------------------------------------------------------
    def start(self, ctx: Context, carry):
        """The per-lane state before the first sample.

        Args:
            ctx: the run's context; carry: the caller's pytree (uniforms may be drawn from it).

        Returns:
            (state, carry): state a pytree of per-lane arrays (never Python floats).
        """
        raise NotImplementedError

    def wants(self, ctx: Context, state):
        """Which lanes need another sample.

        Args:
            ctx: the run's context; state: the current state.

        Returns:
            A per-lane mask (Dr.Jit Bool or numpy bool (lanes, 1)).
        """
        raise NotImplementedError

    def feed(self, ctx: Context, state, x, mask, carry):
        """Take one sample into the state.

        Args:
            ctx: the run's context; state: the current state.
            x: the sample (``Context.adopt``'s layout); mask: the lanes that wanted it (others keep
                their state); carry: the caller's pytree.

        Returns:
            (state, carry) after the sample.
        """
        raise NotImplementedError

    def value(self, ctx: Context, state):
        """The estimate from the final state.

        Args:
            ctx: the run's context; state: the state after the loop.

        Returns:
            The per-lane estimate (like_t, or numpy (lanes, C)).
        """
        raise NotImplementedError

    def next_u(self, ctx: Context, state):
        """The stratified first dimension of the next draw.

        Args:
            ctx: the run's context; state: the current state.

        Returns:
            Per-lane uniforms for draw(carry, u), or None (draw(carry); the default).
        """
        return None

    def exact(self, I):
        """The function this estimator's expectation equals (for Direct: the target g).

        Args:
            I: the expected input, numpy or Dr.Jit.

        Returns:
            The value the estimates average to at I (numpy or Dr.Jit, as I).
        """
        raise NotImplementedError

    @property
    def mean_draws(self):
        """Expected draw() calls per estimate; None where it depends on the data (adaptive
        truncation)."""
        raise NotImplementedError

    @property
    def fixed_draws(self) -> bool:
        """True when every estimate draws exactly ``mean_draws`` samples."""
        return False

    @property
    def uses_comb(self) -> bool:
        return False

    # -- algebra sugar ----------------------------------------------------------------------------
    def __add__(self, other):
        return combinator("sum")(self, other)

    def __mul__(self, other):
        return combinator("product")(self, other)

    def __repr__(self):
        return f"<{type(self).__name__} {self.name}>"

    # -- the kernel contract ----------------------------------------------------------------------
    def run(self, draw, carry, uniform, active=None, *, like=None):
        """One estimate per lane: the kernel contract (package docstring).

        Args:
            draw: draw(carry) -> (x, carry), one sample per lane; called once per loop iteration,
                in the loop body only, on the lanes that still want one. With a stratified comb:
                draw(carry, u), u the first primary dimension to use.
            carry: an opaque pytree; uniform: uniform(carry) -> (u, carry), one per lane.
            active: the lanes that take part (Dr.Jit Bool or numpy bool), None: all.
            like: the type or an instance of x (e.g. mi.Color3f); required for Dr.Jit.

        Returns:
            (value, carry): the estimates (0 on inactive lanes), in x's layout; carry after them.
        """
        return self._run(draw, carry, uniform, active, like)

    def _run(self, draw, carry, uniform, active, like, observe=None):
        """``run``'s loop; ``observe(state)`` (optional) sees the final state before the value is
        taken."""
        ctx, carry = Context.for_run(like, active, uniform, carry)
        if ctx.is_drjit:
            act = active if active is not None else ctx.mask(True)
        else:
            act = (np.ones((ctx.lanes, 1), bool) if active is None
                   else np.asarray(active, bool).reshape(-1, 1))
        state, carry = self.start(ctx, carry)

        def cond(state, carry, act):
            return self.wants(ctx, state) & act

        def body(state, carry, act):
            u = self.next_u(ctx, state)
            if u is None:
                x, carry = draw(carry)
            else:
                x, carry = draw(carry, ctx.user_u(u))
            x = ctx.adopt(x)
            state, carry = self.feed(ctx, state, x, self.wants(ctx, state), carry)
            return state, carry, act

        state, carry, act = ctx.while_loop((state, carry, act), cond, body)
        if observe is not None:
            observe(state)
        return ctx.finish(self.value(ctx, state), active), carry
