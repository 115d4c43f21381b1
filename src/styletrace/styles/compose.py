"""compose: styles applied one after another as one style (supplement S5.4, Fig. 10; Theorem 4.1).

`--style contrast+sepia` applies contrast, then sepia:  g(<I>) = g_k( ... g_2(g_1(<I>)) ... ).

Parameters
- OPERAND.PARAM (default: the operand's own default): each operand's parameters under its name,
  e.g. `contrast.c`, `sepia.gradient`. A style may appear once.

Estimators: all operands affine: `affine`, `combined`; all with a form: `combined` (Theorem 4.1);
otherwise `direct` (and `telescoping` where every operand has a form). Per-sample baselines (acp)
cannot be composed (docs/design/estimator_algebra.md).
"""
from __future__ import annotations

from dataclasses import replace
from typing import Any

import numpy as np

from styletrace.errors import StyleError
from styletrace.styles.base import Style, Vertex
from styletrace.styles.forms import AffineForm, CompositeForm

SEPARATOR = "+"


def is_composite(name: str) -> bool:
    """Whether a style name is a composition.

    Args:
        name: a style name.

    Returns:
        True where it contains SEPARATOR ('+').
    """
    return SEPARATOR in name


def affine_matrix(form: AffineForm) -> tuple[np.ndarray, np.ndarray]:
    """(A, b) as a 3x3 matrix and a 3-vector, whatever shapes the form's a1 and a0 have.

    Args:
        form: the AffineForm (a1 a scalar, 3-vector or 3x3 matrix; a0 a scalar or 3-vector).

    Returns:
        (A, b), float64, with g(I) = A I + b.
    """
    a1 = np.asarray(form.a1, dtype=np.float64)
    A = a1 if a1.ndim == 2 else np.diag(np.broadcast_to(a1, (3,)))
    b = np.broadcast_to(np.asarray(form.a0, dtype=np.float64), (3,)).copy()
    return A, b


def composite_class(name: str, lookup) -> type[Style]:
    """The Style class of `name` = 'a+b+...', its parameters named 'operand.param'.

    Args:
        name: the composition, operands joined by '+' in application order.
        lookup: lookup(op) -> the operand's Style class (raises StyleError for an unknown one).

    Returns:
        A new subclass of Composite.

    Raises:
        StyleError: fewer than two operands, or an unknown, repeated, per-sample or composite one.
    """
    ops = [o.strip() for o in name.split(SEPARATOR)]
    if len(ops) < 2 or any(not o for o in ops):
        raise StyleError(f"bad style {name!r}: a composition is 'STYLE+STYLE[+...]', e.g. "
                         "contrast+sepia")
    if len(set(ops)) != len(ops):
        raise StyleError(
            f"bad style {name!r}: each style may appear once in a composition (its parameters are "
            f"named after it)"
        )
    classes = [lookup(o) for o in ops]
    for cls in classes:
        if cls.per_sample or is_composite(cls.name):
            raise StyleError(
                f"bad style {name!r}: '{cls.name}' cannot be composed (it is not a function of "
                f"an expectation)"
                if cls.per_sample
                else f"bad style {name!r}: nested composition"
            )
    params = tuple(replace(p, name=f"{cls.name}.{p.name}", doc=f"{cls.name}: {p.doc}")
                   for cls in classes for p in cls.params)
    # the first operand sees the radiance: if it ignores it (closed form), so does the whole
    # composition
    inner = 0 if classes[0].default_inner == 0 else max(c.default_inner for c in classes)
    summary = " then ".join(ops) + ", as one style g = " + " o ".join(reversed(ops))
    return type(
        f"Composite[{name}]",
        (Composite,),
        {
            "name": name,
            "summary": summary,
            "params": params,
            "default_inner": inner,
            "operand_classes": tuple(classes),
        },
    )


class Composite(Style):
    """Base of the classes `composite_class` makes; `operand_classes` in application order.

    Args:
        **values: 'operand.param' -> value; each operand is made from its own.

    Raises:
        StyleError: an unknown parameter, or a bad value.
    """

    operand_classes: tuple[type[Style], ...] = ()

    def __init__(self, **values: Any):
        super().__init__(**values)
        self.operands = []
        for cls in self.operand_classes:
            prefix = cls.name + "."
            own = {k[len(prefix):]: v for k, v in self.values.items() if k.startswith(prefix)}
            self.operands.append(cls(**own))

    def prepare(self, scene) -> None:
        for op in self.operands:
            op.prepare(scene)

    def auto_values(self, facts) -> dict:
        """Each operand's auto values, under its prefix; an operand's brightness is that of the
        operands before it applied to the scene (`facts.mapped`), as it sees it in the kernel."""
        out = {}
        for op in self.operands:
            own = op.auto_values(facts)
            out.update({f"{op.name}.{k}": v for k, v in own.items()})
            facts = facts.mapped(op.pinned(own) if own else op)
        return out

    def apply(self, I, v: Vertex):
        for op in self.operands:
            I = op.apply(I, v)
        return I

    def form(self):
        forms = [op.form() for op in self.operands]
        if any(f is None for f in forms):
            return None
        affine = None
        if all(isinstance(f, AffineForm) for f in forms):
            A, b = np.eye(3), np.zeros(3)
            for f in forms:
                Ak, bk = affine_matrix(f)
                A, b = Ak @ A, Ak @ b + bk
            affine = AffineForm(A.tolist(), b.tolist())
        return CompositeForm(tuple(forms), affine)


__all__ = ["Composite", "composite_class", "is_composite", "affine_matrix", "SEPARATOR"]
