"""Build-your-own group-unbiased estimators: sum, product and composition (Theorem 4.1).

Reference: West & Mukherjee, Theorem 4.1: <A> + <B> is gu for gA + gB (samples may be shared); <A>
<B> for gA gB with independent sample groups; independent gu estimates of gB(I) fed to a gu
estimator of gA give gA(gB(I)).

`Sum(*parts, shared=True)`: shared, every draw goes to every part that still wants one (cost: the
largest part's; no comb-stratified parts); unshared, parts draw in turn. `Product(*factors)`:
factors draw in turn. `Compose(outer, inner)`: each outer sample is a fresh inner estimate.
`inner_mean(estimator, m, comb=False)` = Compose(estimator, Mean(m, comb)). mean_draws: shared Sum
-> max of fixed parts, else None; unshared Sum and Product -> the sum; Compose -> the product.
"""
from __future__ import annotations

from styletrace.estimators import arrays as A
from styletrace.estimators.affine import Mean
from styletrace.estimators.base import Context, Estimator, register_combinator

__all__ = ["Sum", "Product", "Compose", "inner_mean"]


def _check_parts(parts, what):
    if not parts:
        raise ValueError(f"{what} needs at least one estimator")
    for p in parts:
        if not isinstance(p, Estimator):
            raise ValueError(f"{what} takes Estimator instances, got {p!r}")
    return tuple(parts)


class _Sequential(Estimator):
    """Parts that draw one after the other (independent sample groups)."""

    def start(self, ctx: Context, carry):
        states = []
        for p in self.parts:
            s, carry = p.start(ctx, carry)
            states.append(s)
        return tuple(states), carry

    def wants(self, ctx, state):
        w = self.parts[0].wants(ctx, state[0])
        for p, s in zip(self.parts[1:], state[1:]):
            w = w | p.wants(ctx, s)
        return w

    def feed(self, ctx, state, x, mask, carry):
        states = list(state)
        free = mask
        for i, p in enumerate(self.parts):
            w = p.wants(ctx, states[i])
            take = free & w
            states[i], carry = p.feed(ctx, states[i], x, take, carry)
            free = free & ~w
        return tuple(states), carry

    def next_u(self, ctx, state):
        us = [p.next_u(ctx, s) for p, s in zip(self.parts, state)]
        if all(u is None for u in us):
            return None
        out = us[-1]
        for p, s, u in reversed(list(zip(self.parts[:-1], state[:-1], us[:-1]))):
            out = A.select(p.wants(ctx, s), u, out)
        return out

    @property
    def uses_comb(self):
        return any(p.uses_comb for p in self.parts)

    @property
    def fixed_draws(self):
        return all(p.fixed_draws for p in self.parts)

    def _check_comb(self):
        flags = [p.uses_comb for p in self.parts]
        if any(flags) and not all(flags):
            raise ValueError("either all or none of the parts may use a comb: the draw signature "
                             "draw(carry, u) vs draw(carry) is fixed per kernel")

    @property
    def mean_draws(self):
        ms = [p.mean_draws for p in self.parts]
        return None if any(m is None for m in ms) else float(sum(ms))


class Sum(_Sequential):
    """<A> + <B> + ...: group-unbiased for gA + gB + ... (Theorem 4.1).

    Args:
        *parts: the estimators summed (at least one).
        shared: every draw goes to every part that still wants one (cost: the largest part's; no
            comb-stratified parts); False: the parts draw in turn (all or none use a comb).

    Raises:
        ValueError: no parts, a part not an Estimator, or comb use that does not fit `shared`.
    """

    def __init__(self, *parts, shared: bool = True):
        self.parts = _check_parts(parts, "Sum")
        self.shared = bool(shared)
        if self.shared and any(p.uses_comb for p in self.parts):
            raise ValueError("a shared Sum cannot hold comb-stratified parts; use shared=False")
        if not self.shared:
            self._check_comb()
        self.name = (("sum(" if self.shared else "sum-unshared(")
                     + ", ".join(p.name for p in self.parts) + ")")

    def feed(self, ctx, state, x, mask, carry):
        if not self.shared:
            return super().feed(ctx, state, x, mask, carry)
        wants = [p.wants(ctx, s) for p, s in zip(self.parts, state)]
        states = list(state)
        for i, p in enumerate(self.parts):
            states[i], carry = p.feed(ctx, states[i], x, mask & wants[i], carry)
        return tuple(states), carry

    def next_u(self, ctx, state):
        return None if self.shared else super().next_u(ctx, state)

    def value(self, ctx, state):
        out = self.parts[0].value(ctx, state[0])
        for p, s in zip(self.parts[1:], state[1:]):
            out = out + p.value(ctx, s)
        return out

    def exact(self, I):
        out = self.parts[0].exact(I)
        for p in self.parts[1:]:
            out = out + p.exact(I)
        return out

    @property
    def mean_draws(self):
        if not self.shared:
            return super().mean_draws
        if all(p.fixed_draws for p in self.parts):
            return float(max(p.mean_draws for p in self.parts))
        return None


class Product(_Sequential):
    """<A> <B> ...: group-unbiased for gA gB ..., the factors drawing independent groups in turn.

    Args:
        *factors: the estimators multiplied (at least one; all or none use a comb).

    Raises:
        ValueError: no factors, a factor not an Estimator, or only some using a comb.
    """

    def __init__(self, *factors):
        self.parts = _check_parts(factors, "Product")
        self._check_comb()
        self.name = "product(" + ", ".join(p.name for p in self.parts) + ")"

    def value(self, ctx, state):
        out = self.parts[0].value(ctx, state[0])
        for p, s in zip(self.parts[1:], state[1:]):
            out = out * p.value(ctx, s)
        return out

    def exact(self, I):
        out = self.parts[0].exact(I)
        for p in self.parts[1:]:
            out = out * p.exact(I)
        return out


class Compose(Estimator):
    """gA(gB(I)): each sample the outer estimator takes is a fresh estimate of the inner one.

    Args:
        outer: the estimator of gA (it cannot use a comb: it receives estimates, not draws).
        inner: the estimator of gB, which consumes the draws.

    Raises:
        ValueError: either is not an Estimator, or the outer one uses a comb.
    """

    def __init__(self, outer: Estimator, inner: Estimator):
        _check_parts((outer, inner), "Compose")
        if outer.uses_comb:
            raise ValueError(
                "the outer estimator of a composition receives inner estimates, not draws: "
                "it cannot use a comb (put the comb on the inner estimator)"
            )
        self.outer, self.inner = outer, inner
        self.name = f"{outer.name} o {inner.name}"

    def _settle(self, ctx, so, si, carry, mask):
        """Feed finished inner estimates to the outer one until the inner one needs a draw."""
        def cond(so, si, carry, mask):
            return mask & self.outer.wants(ctx, so) & ~self.inner.wants(ctx, si)

        def body(so, si, carry, mask):
            m = mask & self.outer.wants(ctx, so) & ~self.inner.wants(ctx, si)
            y = self.inner.value(ctx, si)
            so, carry = self.outer.feed(ctx, so, y, m, carry)
            fresh, carry = self.inner.start(ctx, carry)
            si = A.tree_select(m, fresh, si)
            return so, si, carry, mask

        so, si, carry, mask = ctx.while_loop((so, si, carry, mask), cond, body)
        return so, si, carry

    def start(self, ctx: Context, carry):
        so, carry = self.outer.start(ctx, carry)
        si, carry = self.inner.start(ctx, carry)
        so, si, carry = self._settle(ctx, so, si, carry, ctx.mask(True))
        return (so, si), carry

    def wants(self, ctx, state):
        return self.outer.wants(ctx, state[0])

    def next_u(self, ctx, state):
        return self.inner.next_u(ctx, state[1])

    def feed(self, ctx, state, x, mask, carry):
        so, si = state
        si, carry = self.inner.feed(ctx, si, x, mask & self.inner.wants(ctx, si), carry)
        so, si, carry = self._settle(ctx, so, si, carry, mask)
        return (so, si), carry

    def value(self, ctx, state):
        return self.outer.value(ctx, state[0])

    def exact(self, I):
        return self.outer.exact(self.inner.exact(I))

    @property
    def uses_comb(self):
        return self.inner.uses_comb

    @property
    def fixed_draws(self):
        return self.outer.fixed_draws and self.inner.fixed_draws

    @property
    def mean_draws(self):
        mo, mi = self.outer.mean_draws, self.inner.mean_draws
        return None if mo is None or mi is None else float(mo * mi)


def inner_mean(estimator: Estimator, m: int, comb: bool = False) -> Compose:
    """Feed `estimator` means of m draws (comb-stratified if asked) instead of single draws.

    Args:
        estimator: the outer estimator.
        m: draws per inner mean (>= 1); comb: stratify them with the comb.

    Returns:
        Compose(estimator, Mean(m, comb)).
    """
    return Compose(estimator, Mean(m, comb))


# the operator sugar on every Estimator (base.py imports nothing from here: it looks these up)
register_combinator("sum", Sum)
register_combinator("product", Product)
