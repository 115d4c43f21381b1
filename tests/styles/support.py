"""Shared helpers of the style tests (tests/styles only): numpy <-> Dr.Jit, vertices, error
checks."""
from __future__ import annotations

import numpy as np
import pytest


def rows(a) -> np.ndarray:
    """(N, 3) float32 array from a list of triples."""
    return np.asarray(a, dtype=np.float32).reshape(-1, 3)


def color(a):
    import mitsuba as mi
    return mi.Color3f(rows(a).T.copy())


def point(a):
    import mitsuba as mi
    return mi.Point3f(rows(a).T.copy())


def vector(a):
    import mitsuba as mi
    return mi.Vector3f(rows(a).T.copy())


def tonp(x) -> np.ndarray:
    """(N, 3) array from a Dr.Jit 3-vector, (N,) from a scalar array."""
    a = np.array(x)
    return a.T if a.ndim == 2 else a


def vertex(p=None, n=None, wo=None, view=(0.0, 0.0, 1.0), N=None):
    """A Vertex of N lanes; missing fields are filled with p = 0, n = wo = +z."""
    import mitsuba as mi

    from styletrace.styles import Vertex
    arrays = [a for a in (p, n, wo) if a is not None]
    if N is None:
        N = len(rows(arrays[0])) if arrays else 1

    def fill(a, default):
        r = rows(default if a is None else a)
        return np.broadcast_to(r, (N, 3)) if len(r) == 1 else r

    return Vertex(
        p=point(fill(p, (0, 0, 0))),
        n=vector(fill(n, (0, 0, 1))),
        wo=vector(fill(wo, (0, 0, 1))),
        view=vector(fill(view, view)),
        depth=mi.UInt32(np.zeros(N, dtype=np.uint32)),
    )


def run(style, I, v=None) -> np.ndarray:
    """style.apply on the (N, 3) radiance I, as an (N, 3) numpy array."""
    I = rows(I)
    if v is None:
        v = vertex(N=len(I))
    return tonp(style.apply(color(I), v))


def rejects(style_name: str, param: str, value, **others):
    """The style refuses `param=value` with a StyleError naming both."""
    from styletrace.styles import StyleError, create
    with pytest.raises(StyleError) as info:
        create(style_name, **{param: value}, **others)
    msg = str(info.value)
    assert param in msg, msg
    spellings = {str(value), repr(value)}
    if isinstance(value, (int, float)) and not isinstance(value, bool):
        spellings.add(f"{value:g}")
    assert any(s in msg for s in spellings), msg
    return msg


def rejects_unknown(style_name: str):
    from styletrace.styles import StyleError, create
    with pytest.raises(StyleError, match="unknown parameter 'nonsense'"):
        create(style_name, nonsense=1)
