"""Running estimators on numpy with known test distributions (for tests, benchmarks and docs).

`estimate_numpy(estimator, dist, lanes, rng, channels=None, dtype=np.float64, active=None)` runs
`Estimator.run` with a draw/uniform pair that counts draws per lane; dist is a Distribution here or
a callable sample(rng, size); channels=C gives (lanes, C) values with channel c = (1 + c) x. Returns
NumpyEstimate(values, draws). `estimate_drjit(estimator, dist, lanes, seed=0, channels=None,
like=None, active=None)` does the same inside a Dr.Jit kernel (PCG32 uniforms through the quantile
function). The distributions (`Uniform`, `Exponential`, `TwoPoint`) have closed-form mean, variance
and quantile.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from styletrace.estimators import arrays as A

__all__ = ["Distribution", "Uniform", "Exponential", "TwoPoint", "estimate_numpy",
           "estimate_drjit", "NumpyEstimate", "channel_means"]


class Distribution:
    """A test distribution of X with a closed-form `mean` and `var` (set by each subclass)."""

    mean: float
    var: float

    def quantile(self, u):
        """The quantile function F^-1(u).

        Args:
            u: uniforms in [0, 1), numpy or Dr.Jit.

        Returns:
            Samples of X, of u's kind.
        """
        raise NotImplementedError

    def sample(self, rng, size, u=None):
        """Samples of X by the quantile function.

        Args:
            rng: a numpy Generator; size: the output shape.
            u: the uniforms to use instead of rng's (a comb's), or None.

        Returns:
            numpy samples.
        """
        return self.quantile(rng.random(size) if u is None else np.asarray(u))

    def moment(self, k: int) -> float:
        """E[X^k] (numerically, from the quantile on a fine midpoint grid unless overridden).

        Args:
            k: the order.

        Returns:
            The moment.
        """
        u = (np.arange(200000) + 0.5) / 200000
        return float(np.mean(self.quantile(u) ** k))


@dataclass
class Uniform(Distribution):
    """Uniform on [lo, hi]."""

    lo: float = 0.0
    hi: float = 1.0

    def __post_init__(self):
        self.mean = 0.5 * (self.lo + self.hi)
        self.var = (self.hi - self.lo) ** 2 / 12.0

    def quantile(self, u):
        return self.lo + (self.hi - self.lo) * u

    def moment(self, k):
        return (self.hi ** (k + 1) - self.lo ** (k + 1)) / ((k + 1) * (self.hi - self.lo))


@dataclass
class Exponential(Distribution):
    """shift + an exponential of mean `scale`."""

    scale: float = 1.0
    shift: float = 0.0

    def __post_init__(self):
        self.mean = self.shift + self.scale
        self.var = self.scale ** 2

    def quantile(self, u):
        if A.is_drjit(u):
            return self.shift - self.scale * A.log(1.0 - u)
        return self.shift - self.scale * np.log1p(-np.asarray(u))


@dataclass
class TwoPoint(Distribution):
    """v0 with probability 1 - p, v1 with probability p (a two-point mixture)."""
    v0: float = 0.0
    v1: float = 1.0
    p: float = 0.5

    def __post_init__(self):
        self.mean = (1 - self.p) * self.v0 + self.p * self.v1
        self.var = self.p * (1 - self.p) * (self.v1 - self.v0) ** 2

    def quantile(self, u):
        return A.select(u < 1 - self.p, self.v0 + u * 0.0, self.v1 + u * 0.0)

    def moment(self, k):
        return (1 - self.p) * self.v0 ** k + self.p * self.v1 ** k


def channel_means(dist: Distribution, channels=None):
    """E[x] per channel under the harness' channel convention (channel c = (1 + c) x).

    Args:
        dist: the distribution of x; channels: C, or None for scalar values.

    Returns:
        dist.mean, or numpy (C,).
    """
    if channels is None:
        return dist.mean
    return dist.mean * (1.0 + np.arange(channels))


@dataclass
class NumpyEstimate:
    """The estimates, one per lane ((lanes,) or (lanes, C)), and the draws each used (lanes,)."""

    values: np.ndarray
    draws: np.ndarray

    @property
    def mean(self):
        return self.values.mean(axis=0)

    @property
    def var(self):
        return self.values.var(axis=0, ddof=1)

    @property
    def stderr(self):
        return np.sqrt(self.var / self.values.shape[0])


def estimate_numpy(estimator, dist, lanes: int, rng, channels=None, dtype=np.float64,
                   active=None) -> NumpyEstimate:
    """One estimate per lane with draws from `dist`, counting the draws per lane.

    Args:
        estimator: the estimator to run (`Estimator.run`).
        dist: a Distribution, or a callable sample(rng, size[, u]).
        lanes: the lane count; rng: a numpy Generator for draws and uniforms.
        channels: C for (lanes, C) values, channel c = (1 + c) x; None: (lanes,).
        dtype: the samples' dtype; active: the lanes that take part (bool (lanes,)), or None.

    Returns:
        NumpyEstimate(values, draws).
    """
    sample = dist.sample if isinstance(dist, Distribution) else dist

    def draw(carry, u=None):
        n = carry["draws"].shape[0]
        x = sample(rng, (n,)) if u is None else sample(rng, (n,), np.asarray(u))
        x = np.asarray(x, dtype=np.float64)
        if channels is not None:
            x = x[:, None] * (1.0 + np.arange(channels))
        carry = dict(carry, draws=carry["draws"] + 1)
        return x.astype(dtype), carry

    def uniform(carry):
        return rng.random(carry["draws"].shape[0]), carry

    carry = {"draws": np.zeros(lanes, np.int64)}
    like = np.zeros((lanes,) if channels is None else (lanes, channels), dtype=dtype)
    values, carry = estimator.run(draw, carry, uniform, active=active, like=like)
    return NumpyEstimate(values, carry["draws"])


def estimate_drjit(
    estimator, dist: Distribution, lanes: int, seed: int = 0, channels=None, like=None, active=None
) -> NumpyEstimate:
    """One estimate per lane inside a Dr.Jit loop whose carry holds a PCG32 and a draw counter.

    Args:
        estimator, dist: what to run, and a Distribution whose quantile maps PCG32 uniforms.
        lanes, seed, active: the lane count, the PCG32 seed, the lanes taking part (or None).
        channels: None (Float) or 3 (Array3f, channel c = (1 + c) x); like: the value type or None.

    Returns:
        NumpyEstimate(values, draws), copied to numpy.

    Raises:
        ValueError: channels other than None or 3.
    """
    if channels not in (None, 3):
        raise ValueError("estimate_drjit supports channels=None (Float) or 3 (Array3f), got "
                         f"{channels!r}")
    # like's backend, else the one in use (drjit.llvm, drjit.cuda, .ad)
    m = A.backend_module(like)
    dr = A.drjit()
    PCG32, UInt32 = m.PCG32, m.UInt32
    if like is not None and not isinstance(like, type):
        like = type(like)  # an instance stands for its type
    vt = like if like is not None else (m.Float if channels is None else m.Array3f)
    scale = 1.0 + np.arange(3)

    def draw(carry, u=None):
        rng, count = carry
        if u is None:
            u = rng.next_float32()
        x = dist.quantile(u)
        if channels is not None:
            x = vt(*[x * float(s) for s in scale])
        return x, (rng, count + 1)

    def uniform(carry):
        rng, count = carry
        return rng.next_float32(), (rng, count)

    rng = PCG32(size=lanes, initstate=UInt32(seed * 7919 + 17), initseq=dr.arange(UInt32, lanes))
    carry = (rng, dr.zeros(UInt32, lanes))
    value, carry = estimator.run(draw, carry, uniform, active=active, like=vt)
    dr.eval(value, carry[1])
    v = np.asarray(value, dtype=np.float64)
    return NumpyEstimate(v.T if channels is not None else v, np.asarray(carry[1]).astype(np.int64))
