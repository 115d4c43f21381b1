"""identity: g(I) = I.

Physically based rendering as a special case of the stylized rendering equation. No parameters.
With it, the `stylized` integrator converges to Mitsuba's `path` integrator (a test checks this).
"""
from __future__ import annotations

from styletrace.gate import mi
from styletrace.styles.base import Style, Vertex
from styletrace.styles.forms import AffineForm
from styletrace.styles.registry import register_style


@register_style
class Identity(Style):
    name = "identity"
    summary = "physically based rendering: g(I) = I"
    default_inner = 1

    def apply(self, I: mi.Color3f, v: Vertex) -> mi.Color3f:
        return I

    def form(self):
        return AffineForm(1.0, 0.0)
